//! [`Lanes`]: `L` real numbers that travel together through generic numeric code, so that one
//! evaluation of a block carries `L` independent dual or hyper-dual seeds.
//!
//! The collocation problem differentiates every constraint block by forward-mode AD: one
//! `Dual64` evaluation per Jacobian column, one `HyperDual64` evaluation per Hessian pair. Most of
//! the cost of such an evaluation is not the derivative arithmetic but the work around it
//! (kinematics recursions, array initialization, bookkeeping), repeated for every seed. With
//! `Dual<Lanes<L>>` / `HyperDual<Lanes<L>>` from `num_dual`, one pass evaluates `L` seeds: the
//! dual-number rules are num-dual's own, applied lane by lane, and every lane performs exactly
//! the floating-point operations of the scalar `f64` type in the same order, so lane `l` is bit
//! for bit the scalar evaluation of seed `l` (the unit tests check it).
//!
//! The real parts of the lanes are all equal in this use (every seed evaluates the same point):
//! comparisons, [`DualStruct::re`] and the sign queries read the first lane, so control flow is
//! that of the scalar code, and transcendental functions of equal lanes are computed once.

use num_dual::{DualNum, DualStruct, Mappable};
use num_traits::{FromPrimitive, Inv, Num, One, Signed, Zero};
use std::fmt;
use std::iter::{Product, Sum};
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

/// `L` `f64` values operated on element by element (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Lanes<const L: usize>(pub [f64; L]);

impl<const L: usize> Lanes<L> {
    /// Every lane `v`.
    #[inline]
    pub fn splat(v: f64) -> Self {
        Self([v; L])
    }

    #[inline]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self(self.0.map(f))
    }

    #[inline]
    fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut out = self.0;
        for (o, b) in out.iter_mut().zip(other.0) {
            *o = f(*o, b);
        }
        Self(out)
    }

    /// Whether every lane holds the same bits.
    #[inline]
    fn is_uniform(&self) -> bool {
        let first = self.0[0].to_bits();
        self.0.iter().all(|v| v.to_bits() == first)
    }

    /// `f` lane by lane, computed once when every lane holds the same bits (the real part of
    /// a multi-seed evaluation): the same result, without `L` calls of a costly function.
    #[inline]
    fn map_costly(self, f: impl Fn(f64) -> f64) -> Self {
        if self.is_uniform() {
            Self::splat(f(self.0[0]))
        } else {
            self.map(f)
        }
    }

    /// [`Self::map_costly`] for a function of two lane vectors.
    #[inline]
    fn zip_costly(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        if self.is_uniform() && other.is_uniform() {
            Self::splat(f(self.0[0], other.0[0]))
        } else {
            self.zip(other, f)
        }
    }
}

macro_rules! binary_ops {
    ($trait:ident, $method:ident, $assign_trait:ident, $assign_method:ident, $op:tt) => {
        impl<const L: usize> $trait for Lanes<L> {
            type Output = Self;
            #[inline]
            fn $method(self, other: Self) -> Self {
                self.zip(other, |a, b| a $op b)
            }
        }
        impl<const L: usize> $trait<&Lanes<L>> for Lanes<L> {
            type Output = Self;
            #[inline]
            fn $method(self, other: &Self) -> Self {
                self.zip(*other, |a, b| a $op b)
            }
        }
        impl<const L: usize> $trait<f64> for Lanes<L> {
            type Output = Self;
            #[inline]
            fn $method(self, other: f64) -> Self {
                self.map(|a| a $op other)
            }
        }
        impl<const L: usize> $assign_trait for Lanes<L> {
            #[inline]
            fn $assign_method(&mut self, other: Self) {
                *self = *self $op other;
            }
        }
        impl<const L: usize> $assign_trait<f64> for Lanes<L> {
            #[inline]
            fn $assign_method(&mut self, other: f64) {
                *self = *self $op other;
            }
        }
    };
}

binary_ops!(Add, add, AddAssign, add_assign, +);
binary_ops!(Sub, sub, SubAssign, sub_assign, -);
binary_ops!(Mul, mul, MulAssign, mul_assign, *);
binary_ops!(Div, div, DivAssign, div_assign, /);
binary_ops!(Rem, rem, RemAssign, rem_assign, %);

impl<const L: usize> Neg for Lanes<L> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
}

impl<const L: usize> Zero for Lanes<L> {
    #[inline]
    fn zero() -> Self {
        Self::splat(0.0)
    }
    #[inline]
    fn is_zero(&self) -> bool {
        self.0[0].is_zero()
    }
}

impl<const L: usize> One for Lanes<L> {
    #[inline]
    fn one() -> Self {
        Self::splat(1.0)
    }
    #[inline]
    fn is_one(&self) -> bool {
        self.0[0].is_one()
    }
}

/// Compares the first lanes (all lanes share the real part, see the module docs).
impl<const L: usize> PartialEq for Lanes<L> {
    #[inline]
    fn eq(&self, other: &Self) -> bool {
        self.0[0] == other.0[0]
    }
}

impl<const L: usize> PartialEq<f64> for Lanes<L> {
    #[inline]
    fn eq(&self, other: &f64) -> bool {
        self.0[0] == *other
    }
}

impl<const L: usize> PartialOrd for Lanes<L> {
    #[inline]
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.0[0].partial_cmp(&other.0[0])
    }
}

impl<const L: usize> PartialOrd<f64> for Lanes<L> {
    #[inline]
    fn partial_cmp(&self, other: &f64) -> Option<std::cmp::Ordering> {
        self.0[0].partial_cmp(other)
    }
}

impl<const L: usize> Num for Lanes<L> {
    type FromStrRadixErr = <f64 as Num>::FromStrRadixErr;
    fn from_str_radix(text: &str, radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        f64::from_str_radix(text, radix).map(Self::splat)
    }
}

impl<const L: usize> Signed for Lanes<L> {
    #[inline]
    fn abs(&self) -> Self {
        self.map(f64::abs)
    }
    #[inline]
    fn abs_sub(&self, other: &Self) -> Self {
        self.zip(*other, |a, b| Signed::abs_sub(&a, &b))
    }
    #[inline]
    fn signum(&self) -> Self {
        self.map(|a| Signed::signum(&a))
    }
    #[inline]
    fn is_positive(&self) -> bool {
        Signed::is_positive(&self.0[0])
    }
    #[inline]
    fn is_negative(&self) -> bool {
        Signed::is_negative(&self.0[0])
    }
}

impl<const L: usize> Inv for Lanes<L> {
    type Output = Self;
    #[inline]
    fn inv(self) -> Self {
        self.map(Inv::inv)
    }
}

impl<const L: usize> Sum for Lanes<L> {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        // -0.0, the neutral element std's f64 sum starts from.
        iter.fold(Self::splat(-0.0), |acc, v| acc + v)
    }
}

impl<const L: usize> Product for Lanes<L> {
    fn product<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::splat(1.0), |acc, v| acc * v)
    }
}

impl<const L: usize> FromPrimitive for Lanes<L> {
    fn from_i64(n: i64) -> Option<Self> {
        f64::from_i64(n).map(Self::splat)
    }
    fn from_u64(n: u64) -> Option<Self> {
        f64::from_u64(n).map(Self::splat)
    }
    fn from_f64(n: f64) -> Option<Self> {
        Some(Self::splat(n))
    }
}

impl<const L: usize> From<f64> for Lanes<L> {
    #[inline]
    fn from(v: f64) -> Self {
        Self::splat(v)
    }
}

impl<const L: usize> fmt::Display for Lanes<L> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.0)
    }
}

impl<const L: usize> DualStruct for Lanes<L> {
    type Real = f64;
    type Inner = f64;
    #[inline]
    fn re(&self) -> f64 {
        self.0[0]
    }
    #[inline]
    fn from_inner(inner: &f64) -> Self {
        Self::splat(*inner)
    }
}

impl<const L: usize> Mappable<Self> for Lanes<L> {
    type Output<O> = O;
    #[inline]
    fn map_dual<M: Fn(Self) -> O, O>(self, f: M) -> O {
        f(self)
    }
}

macro_rules! lanewise {
    ($($name:ident),*) => {
        $(
            #[inline]
            fn $name(&self) -> Self {
                self.map_costly(|a| <f64 as DualNum>::$name(&a))
            }
        )*
    };
}

impl<const L: usize> DualNum for Lanes<L> {
    type Primitive = f64;
    const NDERIV: usize = 0;
    type InnerDual = Self;

    #[inline]
    fn from_re(re: Self) -> Self {
        re
    }
    #[inline]
    fn scale(self, factor: &Self) -> Self {
        self * factor
    }
    #[inline]
    fn mul_add(&self, a: Self, b: Self) -> Self {
        let mut out = self.0;
        for ((o, a), b) in out.iter_mut().zip(a.0).zip(b.0) {
            *o = o.mul_add(a, b);
        }
        Self(out)
    }
    #[inline]
    fn recip(&self) -> Self {
        self.map(f64::recip)
    }
    #[inline]
    fn powi(&self, n: i32) -> Self {
        self.map_costly(|a| a.powi(n))
    }
    #[inline]
    fn powf(&self, n: f64) -> Self {
        self.map_costly(|a| a.powf(n))
    }
    #[inline]
    fn powd(&self, n: Self) -> Self {
        self.zip_costly(n, f64::powf)
    }
    #[inline]
    fn log(&self, base: f64) -> Self {
        self.map_costly(|a| a.log(base))
    }
    #[inline]
    fn atan2(&self, other: Self) -> Self {
        self.zip_costly(other, f64::atan2)
    }
    #[inline]
    fn sin_cos(&self) -> (Self, Self) {
        if self.is_uniform() {
            let (s, c) = self.0[0].sin_cos();
            (Self::splat(s), Self::splat(c))
        } else {
            (self.map(f64::sin), self.map(f64::cos))
        }
    }
    lanewise!(
        sqrt, cbrt, exp, exp2, exp_m1, ln, log2, log10, ln_1p, sin, cos, tan, asin, acos, atan,
        sinh, cosh, tanh, asinh, acosh, atanh, sph_j0, sph_j1, sph_j2
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{Dual, Dual64, HyperDual, HyperDual64};

    /// A function using every operation the collocation blocks use, and some they do not.
    fn f<S: DualNum<Primitive = f64> + Copy>(x: &[S]) -> S {
        let (s, c) = (x[0] * x[1]).sin_cos();
        let r = (x[2] * x[2] + 1.5).sqrt().recip();
        let q = (x[0] - x[2] * 3.0) / (x[1] + 2.0);
        let mut acc = S::zero();
        for v in x {
            acc += *v * s - c * 0.5;
        }
        acc * r + q.powi(3) - x[1].exp() * x[0].cos()
            + (x[2] * 0.3).atan()
            + x[0].mul_add(x[1], x[2])
    }

    const X: [f64; 3] = [0.3, -1.1, 0.7];

    #[test]
    fn every_hyper_dual_lane_is_bit_identical_to_the_scalar_evaluation() {
        let pairs = [(0, 0), (1, 0), (2, 1), (2, 2)];
        let z: Vec<HyperDual<Lanes<4>>> = (0..3)
            .map(|i| {
                let e1 = pairs.map(|(a, _)| if a == i { 1.0 } else { 0.0 });
                let e2 = pairs.map(|(_, b)| if b == i { 1.0 } else { 0.0 });
                HyperDual::new(Lanes::splat(X[i]), Lanes(e1), Lanes(e2), Lanes::zero())
            })
            .collect();
        let laned = f(&z);
        for (l, &(a, b)) in pairs.iter().enumerate() {
            let zs: Vec<HyperDual64> = (0..3)
                .map(|i| {
                    let one = |k| if k == i { 1.0 } else { 0.0 };
                    HyperDual64::new(X[i], one(a), one(b), 0.0)
                })
                .collect();
            let scalar = f(&zs);
            assert_eq!(laned.re.0[l].to_bits(), scalar.re.to_bits());
            assert_eq!(laned.eps1.0[l].to_bits(), scalar.eps1.to_bits());
            assert_eq!(laned.eps2.0[l].to_bits(), scalar.eps2.to_bits());
            assert_eq!(laned.eps1eps2.0[l].to_bits(), scalar.eps1eps2.to_bits());
        }
        // And the second derivative is the true one: central difference of the first.
        let h = 1e-5;
        let grad0 = |x: [f64; 3]| {
            let z: Vec<Dual64> = (0..3)
                .map(|i| Dual64::new(x[i], if i == 0 { 1.0 } else { 0.0 }))
                .collect();
            f(&z).eps
        };
        let (mut up, mut down) = (X, X);
        up[1] += h;
        down[1] -= h;
        let fd = (grad0(up) - grad0(down)) / (2.0 * h);
        assert!((laned.eps1eps2.0[1] - fd).abs() < 1e-7 * (1.0 + fd.abs()));
    }

    #[test]
    fn every_dual_lane_is_bit_identical_to_the_scalar_evaluation() {
        let z: Vec<Dual<Lanes<3>>> = (0..3)
            .map(|i| {
                let mut eps = [0.0; 3];
                eps[i] = 1.0;
                Dual::new(Lanes::splat(X[i]), Lanes(eps))
            })
            .collect();
        let laned = f(&z);
        for l in 0..3 {
            let zs: Vec<Dual64> = (0..3)
                .map(|i| Dual64::new(X[i], if i == l { 1.0 } else { 0.0 }))
                .collect();
            let scalar = f(&zs);
            assert_eq!(laned.re.0[l].to_bits(), scalar.re.to_bits());
            assert_eq!(laned.eps.0[l].to_bits(), scalar.eps.to_bits());
        }
    }

    #[test]
    fn unequal_lanes_take_the_per_lane_path() {
        let v = Lanes([0.1, 0.2, 0.3]);
        let (s, c) = v.sin_cos();
        for l in 0..3 {
            assert_eq!(s.0[l], v.0[l].sin());
            assert_eq!(c.0[l], v.0[l].cos());
        }
        assert_eq!(v.sqrt().0[2], 0.3f64.sqrt());
    }
}
