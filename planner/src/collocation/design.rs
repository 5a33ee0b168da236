//! Co-design inside a block: the design-joint values of its variables and the link mass
//! properties at those lengths (the cubic fits under exact coupling).

use super::blocks::Kind;
use super::problem::HzdProblem;
use model::kinematics::Constant;
use model::robot::BodyInertia;
use model::Real;

impl HzdProblem {
    /// The design-joint values [thigh, shin] of a model block's local variables (its last two
    /// are the total lengths in a co-design), or None without co-design.
    pub(super) fn design_joints_of<S: Real>(&self, kind: Kind, z: &[S]) -> Option<[S; 2]> {
        let d = self.design.as_ref()?;
        if !Self::uses_model(kind) {
            return None;
        }
        let n = z.len();
        Some([
            z[n - 2] - d.spec.nominal_m[0],
            z[n - 1] - d.spec.nominal_m[1],
        ])
    }

    /// The model's own mass properties as constants, unless a model block's depend on its
    /// variables (co-design with exact inertia coupling): then `None`, and
    /// [`Self::inertias_of`] gives them.
    pub(super) fn constant_inertias_for(&self, kind: Kind) -> Option<&[BodyInertia<Constant>]> {
        let exact = self
            .design
            .as_ref()
            .is_some_and(|d| d.spec.exact_inertia && Self::uses_model(kind));
        (!exact).then_some(self.constant_inertias.as_slice())
    }

    /// Body mass properties at the lengths of a model block's local variables: the cubic fits
    /// for thighs and shins under exact coupling, the model's own otherwise. Written into a
    /// caller's fixed array (no allocation or copy per evaluation); the first `bodies.len()`
    /// entries are set.
    pub(super) fn inertias_of<S: Real>(
        &self,
        kind: Kind,
        z: &[S],
        all: &mut [model::robot::BodyInertia<S>; model::robot::MAX_BODIES],
    ) {
        let lift = |i: &model::robot::BodyInertia<f64>| model::robot::BodyInertia {
            mass_kg: S::from(i.mass_kg),
            com_xz_m: [S::from(i.com_xz_m[0]), S::from(i.com_xz_m[1])],
            inertia_yy_kgm2: S::from(i.inertia_yy_kgm2),
        };
        let design = self
            .design
            .as_ref()
            .filter(|d| d.spec.exact_inertia && Self::uses_model(kind));
        let Some(d) = design else {
            for (a, b) in all.iter_mut().zip(&self.biped.model.bodies) {
                *a = lift(&b.inertia);
            }
            return;
        };
        for (a, i) in all.iter_mut().zip(&d.base) {
            *a = lift(i);
        }
        let n = z.len();
        let (lt, ls) = (z[n - 2], z[n - 1]);
        let link = |fit: &model::design::LinkFit, len: S| model::robot::BodyInertia {
            mass_kg: fit.mass_kg.eval(len),
            com_xz_m: [S::zero(), -fit.com_distance_m.eval(len)],
            inertia_yy_kgm2: fit.iyy_kgm2.eval(len),
        };
        for &b in &d.thigh_bodies {
            all[b] = link(&d.fits.thigh, lt);
        }
        for &b in &d.shin_bodies {
            all[b] = link(&d.fits.shin, ls);
        }
    }
}
