//! The contact solver: the model's `D(q)`, `H(q, q̇)` reduced to the coordinates that move (the
//! design joints are rigid, so their rows and columns drop out: the same as the model's
//! `q̈_D = 0` constraint rows), then point-foot constraints by a Schur complement.
//!
//! Every use is one projection: given an unconstrained `w` and target `c` for `J x`, find
//! `x = w + D⁻¹ Jᵀ λ` with `J x = c`. That is the stance dynamics (`w = D⁻¹(Bu − H)`,
//! `c = −J̇q̇`, λ = contact force), the plastic impact (`w = q̇⁻`, `c = 0`, λ = impulse) and
//! the drift corrections (velocity: `w = q̇`, `c = 0`; position: `w = 0`, `c = −error`), all in
//! the kinetic-energy metric. Buffers are sized once; nothing here allocates.

use model::kinematics::BodyStates;
use model::PlanarModel;
use nalgebra::DMatrix;

/// Most simultaneous contact points (two point feet).
pub const MAX_CONTACTS: usize = 2;
const MAX_ROWS: usize = 2 * MAX_CONTACTS;
/// Most coordinates that move (the model's capacity).
pub const MAX_FREE: usize = model::robot::MAX_DOF;

/// Relative Tikhonov term on the contact Schur complement, so that a singular contact
/// Jacobian (a straight knee with both feet pinned) still gives a (least-squares) answer.
const SCHUR_REGULARIZATION: f64 = 1e-12;

/// The Cholesky factorization failed: `D` is not positive definite (a massless chain).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotPositiveDefinite;

/// Preallocated workspace of the reduced constrained dynamics. The factorizations happen when
/// `D` or the contacts are loaded; they are kept as explicit inverses of `D_r` and of the
/// Schur complement, so every projection is a few short matrix-vector products (no serial
/// substitutions and divisions), which is what the simulator repeats at 10 kHz.
#[derive(Debug, Clone)]
pub struct Solver {
    /// Coordinates that move (all but the design joints), ascending.
    free: Vec<usize>,
    /// Cholesky factor L of D_r (row-major, lower triangle used).
    chol: Vec<f64>,
    /// D_r⁻¹ (row-major), from the factor: every later solve is a product with it, whose
    /// rows are independent sums instead of the factor's serial substitutions.
    inverse: Vec<f64>,
    /// Contact Jacobian rows restricted to `free` (row-major, `rows × n_r`).
    jac: Vec<f64>,
    /// D_r⁻¹ Jᵀ, stored as rows (`rows × n_r`).
    y: Vec<f64>,
    /// Inverse of the (regularized) Schur complement J D_r⁻¹ Jᵀ, from its Cholesky factor.
    schur_inverse: [[f64; MAX_ROWS]; MAX_ROWS],
    rows: usize,
}

impl Solver {
    /// A workspace for `model`.
    pub fn new(model: &PlanarModel) -> Self {
        let design: Vec<usize> = model
            .design_joints()
            .iter()
            .map(|&j| model.joints[j].coordinate)
            .collect();
        let free: Vec<usize> = (0..model.dof()).filter(|c| !design.contains(c)).collect();
        let n = free.len();
        Self {
            chol: vec![0.0; n * n],
            inverse: vec![0.0; n * n],
            jac: vec![0.0; MAX_ROWS * n],
            y: vec![0.0; MAX_ROWS * n],
            schur_inverse: [[0.0; MAX_ROWS]; MAX_ROWS],
            rows: 0,
            free,
        }
    }

    /// The coordinates that move.
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// Number of coordinates that move.
    pub fn len(&self) -> usize {
        self.free.len()
    }

    /// Factor and invert the reduced mass matrix `D_r` of the full `D`.
    pub fn factor_mass(&mut self, d: &DMatrix<f64>) -> Result<(), NotPositiveDefinite> {
        let n = self.free.len();
        for (i, &ci) in self.free.iter().enumerate() {
            for (k, &ck) in self.free.iter().enumerate() {
                self.chol[i * n + k] = d[(ci, ck)];
            }
        }
        cholesky(&mut self.chol, n)?;
        inverse_from_cholesky(&self.chol, n, &mut self.inverse);
        Ok(())
    }

    /// `x ← D_r⁻¹ x` in place (`x` in reduced coordinates, at most [`MAX_FREE`] of them).
    pub fn solve_mass(&self, x: &mut [f64]) {
        mul_inverse(&self.inverse, self.free.len(), x);
    }

    /// Load the Jacobians of `frames` at the body states `st` and factor the Schur complement.
    pub fn set_contacts(&mut self, model: &PlanarModel, st: &BodyStates<f64>, frames: &[usize]) {
        let n = self.free.len();
        self.rows = 2 * frames.len().min(MAX_CONTACTS);
        self.jac[..self.rows * n].fill(0.0);
        let free = &self.free;
        let jac = &mut self.jac;
        for (k, &frame) in frames.iter().take(MAX_CONTACTS).enumerate() {
            let p = model.frame_position_in(st, frame);
            model.point_jacobian_into(st, model.frames[frame].body, p, |r, c, v| {
                if let Ok(i) = free.binary_search(&c) {
                    jac[(2 * k + r) * n + i] = v;
                }
            });
        }
        for r in 0..self.rows {
            let (row, y) = (
                &self.jac[r * n..(r + 1) * n],
                &mut self.y[r * n..(r + 1) * n],
            );
            y.copy_from_slice(row);
            mul_inverse(&self.inverse, n, y);
        }
        // The Schur complement J D_r⁻¹ Jᵀ (row-major, `rows × rows`), regularized.
        let rows = self.rows;
        let mut flat = [0.0; MAX_ROWS * MAX_ROWS];
        let mut trace = 0.0;
        for a in 0..rows {
            for b in 0..=a {
                let v = dot(&self.jac[a * n..(a + 1) * n], &self.y[b * n..(b + 1) * n]);
                flat[a * rows + b] = v;
                flat[b * rows + a] = v;
            }
            trace += flat[a * rows + a];
        }
        let eps = SCHUR_REGULARIZATION * trace.max(f64::MIN_POSITIVE);
        for a in 0..rows {
            flat[a * rows + a] += eps;
        }
        // Positive definite by construction (regularized).
        let _ = cholesky(&mut flat[..rows * rows], rows);
        let mut inverse = [0.0; MAX_ROWS * MAX_ROWS];
        inverse_from_cholesky(&flat[..rows * rows], rows, &mut inverse[..rows * rows]);
        for (a, row) in self.schur_inverse.iter_mut().enumerate().take(rows) {
            row[..rows].copy_from_slice(&inverse[a * rows..(a + 1) * rows]);
        }
    }

    /// `J x` for the loaded contacts (`x` reduced), into `out[..rows]`.
    pub fn jacobian_times(&self, x: &[f64], out: &mut [f64; MAX_ROWS]) {
        let n = self.free.len();
        match self.rows {
            4 => *out = dots::<4>(&self.jac, n, x),
            2 => out[..2].copy_from_slice(&dots::<2>(&self.jac, n, x)),
            rows => {
                for (r, o) in out.iter_mut().enumerate().take(rows) {
                    *o = dot(&self.jac[r * n..(r + 1) * n], x);
                }
            }
        }
    }

    /// Project: `w ← w + D⁻¹Jᵀλ` with `J w = c` afterwards; writes λ (one per row).
    pub fn constrain(&self, w: &mut [f64], c: &[f64; MAX_ROWS], lambda: &mut [f64; MAX_ROWS]) {
        let mut jw = [0.0; MAX_ROWS];
        self.jacobian_times(w, &mut jw);
        let mut residual = [0.0; MAX_ROWS];
        for ((r, ci), ji) in residual.iter_mut().zip(c).zip(&jw).take(self.rows) {
            *r = ci - ji;
        }
        self.add_correction(&residual, w, lambda);
    }

    /// The correction `x = D⁻¹Jᵀλ` with `J x = c` (the smallest in the kinetic-energy metric):
    /// [`Self::constrain`] from `w = 0`, without its product `J·0`.
    pub fn correction(&self, c: &[f64; MAX_ROWS], x: &mut [f64]) {
        x[..self.free.len()].fill(0.0);
        self.add_correction(c, x, &mut [0.0; MAX_ROWS]);
    }

    /// `w ← w + D⁻¹Jᵀλ` with `λ = (J D⁻¹ Jᵀ)⁻¹ residual`, written to `lambda`.
    fn add_correction(
        &self,
        residual: &[f64; MAX_ROWS],
        w: &mut [f64],
        lambda: &mut [f64; MAX_ROWS],
    ) {
        let rows = self.rows;
        let n = self.free.len();
        for (l, row) in lambda.iter_mut().zip(&self.schur_inverse).take(rows) {
            *l = dot(&row[..rows], &residual[..rows]);
        }
        for (r, l) in lambda.iter().enumerate().take(rows) {
            for (wi, yi) in w.iter_mut().zip(&self.y[r * n..(r + 1) * n]) {
                *wi += yi * l;
            }
        }
    }

    /// Gather full coordinates into reduced ones.
    pub fn gather(&self, full: &[f64], reduced: &mut [f64]) {
        for (r, &c) in reduced.iter_mut().zip(&self.free) {
            *r = full[c];
        }
    }

    /// `full[free[i]] += scale · reduced[i]`.
    pub fn scatter_add(&self, reduced: &[f64], scale: f64, full: &mut [f64]) {
        for (&r, &c) in reduced.iter().zip(&self.free) {
            full[c] += scale * r;
        }
    }
}

/// `x ← A x` in place for a row-major `n × n` matrix `A`, `n ≤ MAX_FREE`.
fn mul_inverse(a: &[f64], n: usize, x: &mut [f64]) {
    let mut v = [0.0; MAX_FREE];
    v[..n].copy_from_slice(&x[..n]);
    let v = &v[..n];
    let mut blocks = x[..n].chunks_exact_mut(4);
    for (xs, rows) in (&mut blocks).zip(a.chunks_exact(4 * n)) {
        xs.copy_from_slice(&dots::<4>(rows, n, v));
    }
    let done = n - blocks.into_remainder().len();
    for (xi, row) in x[done..n].iter_mut().zip(a[done * n..].chunks_exact(n)) {
        *xi = dot(row, v);
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `[a_0 · x, …, a_{R−1} · x]` for the first `R` rows `a_r` of the row-major `a` (`n` columns):
/// the rows' sums interleaved, each still in index order from −0 (the same bits as [`dot`] row
/// by row), so `R` independent chains of additions run at once instead of one after another.
#[inline]
fn dots<const R: usize>(a: &[f64], n: usize, x: &[f64]) -> [f64; R] {
    let a = &a[..R * n];
    let mut sums = [-0.0; R];
    for (k, &xk) in x[..n].iter().enumerate() {
        for (r, sum) in sums.iter_mut().enumerate() {
            *sum += a[r * n + k] * xk;
        }
    }
    sums
}

/// In-place Cholesky `A = L Lᵀ` of a row-major `n × n` matrix (lower triangle holds L).
fn cholesky(a: &mut [f64], n: usize) -> Result<(), NotPositiveDefinite> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= 0.0 {
            return Err(NotPositiveDefinite);
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    Ok(())
}

/// `A⁻¹ = L⁻ᵀ L⁻¹` into `inverse` (row-major `n × n`, both triangles) from the Cholesky factor
/// `L` of `A` (row-major, lower triangle), `n ≤ MAX_FREE`: `L⁻¹` by forward substitution with
/// the reciprocals of its diagonal (`n` divisions in all), then the product, whose entries are
/// independent sums (LAPACK's `potri`).
fn inverse_from_cholesky(l: &[f64], n: usize, inverse: &mut [f64]) {
    let (l, inverse) = (&l[..n * n], &mut inverse[..n * n]);
    let mut recip = [0.0; MAX_FREE];
    for (r, i) in recip.iter_mut().zip(0..n) {
        *r = 1.0 / l[i * n + i];
    }
    // L⁻¹ (lower triangle, row-major), a column at a time.
    let mut l_inv = [0.0; MAX_FREE * MAX_FREE];
    for j in 0..n {
        l_inv[j * n + j] = recip[j];
        for i in j + 1..n {
            let mut s = 0.0;
            for k in j..i {
                s += l[i * n + k] * l_inv[k * n + j];
            }
            l_inv[i * n + j] = -s * recip[i];
        }
    }
    // (L⁻ᵀ L⁻¹)_ij = Σ_{k ≥ max(i, j)} L⁻¹_ki L⁻¹_kj.
    for i in 0..n {
        for j in i..n {
            let mut s = 0.0;
            for k in j..n {
                s += l_inv[k * n + i] * l_inv[k * n + j];
            }
            inverse[i * n + j] = s;
            inverse[j * n + i] = s;
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::needless_range_loop)]
mod tests {
    use super::*;

    fn adam() -> PlanarModel {
        model::design::generate_model(&model::design::DesignLengths::ADAM)
            .unwrap()
            .0
    }

    /// A bent-knee pose with some velocity, both feet near the ground.
    fn state(m: &PlanarModel) -> (Vec<f64>, Vec<f64>) {
        let mut q = m.nominal_pose().unwrap();
        let legs = m.legs().unwrap();
        for (j, v) in [
            (legs.left.hip, -0.4),
            (legs.left.knee, 0.7),
            (legs.right.hip, 0.1),
            (legs.right.knee, 0.3),
        ] {
            q[m.joints[j].coordinate] = v;
        }
        q[2] = 0.05;
        let mut dq = vec![0.0; m.dof()];
        for (c, v) in [(0, 0.3), (1, -0.2), (2, 0.4)] {
            dq[c] = v;
        }
        dq[m.joints[legs.left.hip].coordinate] = 1.1;
        dq[m.joints[legs.right.knee].coordinate] = -0.8;
        (q, dq)
    }

    #[test]
    fn stance_dynamics_match_the_model() {
        // Independent path: the model's full saddle-point solve with design rows.
        let m = adam();
        let (q, dq) = state(&m);
        let legs = m.legs().unwrap();
        let u = [3.0, -2.0, 5.0, 1.0];
        for frames in [
            vec![],
            vec![legs.left.foot],
            vec![legs.left.foot, legs.right.foot],
        ] {
            let reference = m.constrained_dynamics(&q, &dq, &u, &frames).unwrap();
            let mut s = Solver::new(&m);
            let dy = m.dynamics(&q, &dq).unwrap();
            s.factor_mass(&dy.mass_matrix).unwrap();
            let bu = m.generalized_forces(&u).unwrap();
            let full: Vec<f64> = (0..m.dof()).map(|i| bu[i] - dy.drift[i]).collect();
            let mut acc = vec![0.0; s.len()];
            s.gather(&full, &mut acc);
            s.solve_mass(&mut acc);
            let st = m.body_states(&q, &dq).unwrap();
            s.set_contacts(&m, &st, &frames);
            let mut c = [0.0; MAX_ROWS];
            for (k, &f) in frames.iter().enumerate() {
                let b = m.frame_bias_acceleration_in(&st, f);
                c[2 * k] = -b[0];
                c[2 * k + 1] = -b[1];
            }
            let mut lambda = [0.0; MAX_ROWS];
            s.constrain(&mut acc, &c, &mut lambda);
            let mut ddq = vec![0.0; m.dof()];
            s.scatter_add(&acc, 1.0, &mut ddq);
            for i in 0..m.dof() {
                assert!(
                    (ddq[i] - reference.ddq[i]).abs() < 1e-8 * (1.0 + reference.ddq[i].abs()),
                    "{frames:?} coordinate {i}: {} vs {}",
                    ddq[i],
                    reference.ddq[i]
                );
            }
            for (k, f) in reference.forces_n.iter().enumerate() {
                for r in 0..2 {
                    assert!((lambda[2 * k + r] - f[r]).abs() < 1e-7 * (1.0 + f[r].abs()));
                }
            }
        }
    }

    /// The simulator's accelerations (its D and H from `dynamics_into`, its contact solve) with
    /// the A1 armature of the URDF and viscous friction added satisfy the inverse dynamics the
    /// planner's collocation imposes: D q̈ + H = B u + Jᵀ λ on every coordinate that moves.
    #[test]
    fn stance_dynamics_with_armature_and_friction_satisfy_the_planners_inverse_dynamics() {
        let mass = model::design::MassModel {
            a1_drives: true,
            ..Default::default()
        };
        let (mut m, _) =
            model::design::generate_model_with(&model::design::DesignLengths::ADAM, &mass)
                .expect("ADAM with the A1 drives");
        for j in &mut m.joints {
            if let model::JointKind::Revolute { .. } = j.kind {
                j.drive.damping_nms_per_rad = 0.8;
            }
        }
        assert!(m
            .drives()
            .all(|(_, armature, _)| (armature - 0.01).abs() < 1e-12));
        assert_eq!(m.drives().count(), 4);
        let (q, dq) = state(&m);
        let legs = m.legs().unwrap();
        let u = [3.0, -2.0, 5.0, 1.0];
        let n = m.dof();
        for frames in [vec![], vec![legs.left.foot]] {
            let st = m.body_states(&q, &dq).unwrap();
            let mut mass = nalgebra::DMatrix::zeros(n, n);
            let mut drift = nalgebra::DVector::zeros(n);
            m.dynamics_into(&st, &mut mass, &mut drift).unwrap();
            let mut s = Solver::new(&m);
            s.factor_mass(&mass).unwrap();
            let bu = m.generalized_forces(&u).unwrap();
            let full: Vec<f64> = (0..n).map(|i| bu[i] - drift[i]).collect();
            let mut acc = vec![0.0; s.len()];
            s.gather(&full, &mut acc);
            s.solve_mass(&mut acc);
            s.set_contacts(&m, &st, &frames);
            let mut c = [0.0; MAX_ROWS];
            for (k, &f) in frames.iter().enumerate() {
                let b = m.frame_bias_acceleration_in(&st, f);
                c[2 * k] = -b[0];
                c[2 * k + 1] = -b[1];
            }
            let mut lambda = [0.0; MAX_ROWS];
            s.constrain(&mut acc, &c, &mut lambda);
            let mut ddq = vec![0.0; n];
            s.scatter_add(&acc, 1.0, &mut ddq);
            let tau = m.inverse_dynamics(&q, &dq, &ddq).unwrap();
            let mut rhs: Vec<f64> = bu.iter().copied().collect();
            for (k, &f) in frames.iter().enumerate() {
                let jac = m.frame_jacobian(&st, f);
                for i in 0..n {
                    rhs[i] += jac[(0, i)] * lambda[2 * k] + jac[(1, i)] * lambda[2 * k + 1];
                }
            }
            let design: Vec<usize> = m
                .design_joints()
                .iter()
                .map(|&j| m.joints[j].coordinate)
                .collect();
            for i in (0..n).filter(|i| !design.contains(i)) {
                assert!(
                    (tau[i] - rhs[i]).abs() < 1e-8 * (1.0 + rhs[i].abs()),
                    "{frames:?} coordinate {i}: inverse dynamics {} vs B u + Jᵀλ {}",
                    tau[i],
                    rhs[i]
                );
            }
        }
    }

    #[test]
    fn impact_matches_the_model() {
        let m = adam();
        let (q, dq) = state(&m);
        let legs = m.legs().unwrap();
        let reference = m.impact(&q, &dq, legs.right.foot).unwrap();
        let mut s = Solver::new(&m);
        let dy = m.dynamics(&q, &dq).unwrap();
        s.factor_mass(&dy.mass_matrix).unwrap();
        let st = m.body_poses(&q).unwrap();
        s.set_contacts(&m, &st, &[legs.right.foot]);
        let mut v = vec![0.0; s.len()];
        s.gather(&dq, &mut v);
        let mut lambda = [0.0; MAX_ROWS];
        s.constrain(&mut v, &[0.0; MAX_ROWS], &mut lambda);
        let mut dq_plus = vec![0.0; m.dof()];
        s.scatter_add(&v, 1.0, &mut dq_plus);
        for i in 0..m.dof() {
            assert!((dq_plus[i] - reference.dq_plus[i]).abs() < 1e-9, "{i}");
        }
        assert!((lambda[0] - reference.impulse_ns[0]).abs() < 1e-9);
        assert!((lambda[1] - reference.impulse_ns[1]).abs() < 1e-9);
    }

    #[test]
    fn cholesky_inverts_a_known_matrix() {
        let mut a = [4.0, 2.0, 2.0, 3.0];
        cholesky(&mut a, 2).unwrap();
        let mut inverse = [0.0; 4];
        inverse_from_cholesky(&a, 2, &mut inverse);
        // [4 2; 2 3]⁻¹ = [3 −2; −2 4] / 8.
        for (x, want) in inverse.iter().zip([0.375, -0.25, -0.25, 0.5]) {
            assert!((x - want).abs() < 1e-15, "{inverse:?}");
        }
        let mut bad = [1.0, 2.0, 2.0, 1.0];
        assert_eq!(cholesky(&mut bad, 2), Err(NotPositiveDefinite));
    }
}
