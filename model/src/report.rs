//! Human-readable summaries of a model, for the CLI.

use crate::robot::{JointKind, JointRole, PlanarModel, Side};
use crate::Result;
use std::fmt::Write;

impl PlanarModel {
    /// Links, joints, total mass, leg lengths and D(q) at `q`, as text.
    pub fn summary(&self, q: &[f64]) -> Result<String> {
        let mut s = String::new();
        let w = &mut s;
        let _ = writeln!(
            w,
            "robot '{}': {} bodies, {} joints, {} coordinates (x, z, pitch + joints)",
            self.name,
            self.bodies.len(),
            self.joints.len(),
            self.dof()
        );
        let _ = writeln!(
            w,
            "\nbodies (fixed links merged; mass, com in body frame, I_yy about com):"
        );
        for b in &self.bodies {
            let i = &b.inertia;
            let _ = writeln!(
                w,
                "  {:<22} {:>8.4} kg   com ({:>8.4}, {:>8.4}) m   I_yy {:>9.6} kg·m²",
                b.name, i.mass_kg, i.com_xz_m[0], i.com_xz_m[1], i.inertia_yy_kgm2
            );
        }
        let _ = writeln!(w, "\njoints:");
        for j in &self.joints {
            let (kind, unit) = match j.kind {
                JointKind::Revolute { .. } => ("revolute", "rad"),
                JointKind::Prismatic { .. } => ("prismatic", "m"),
            };
            let role = match j.role {
                JointRole::Actuated => "actuated",
                JointRole::Design => "design",
            };
            let _ = writeln!(
                w,
                "  q[{:>2}] {:<20} {:<9} {:<8} [{:>7.3}, {:>7.3}] {:<3}  effort {:>5.1}  velocity {:>5.1}  at {:>8.4}",
                j.coordinate, j.name, kind, role, j.lower, j.upper, unit, j.effort_limit, j.velocity_limit, q[j.coordinate]
            );
        }
        let _ = writeln!(w, "\ntotal mass {:.4} kg", self.total_mass_kg());
        if self.legs().is_ok() {
            for side in [Side::Left, Side::Right] {
                let (t, sh) = self.leg_lengths(q, side)?;
                let _ = writeln!(
                    w,
                    "{:<5} leg: thigh {:.4} m, shin {:.4} m",
                    side.prefix(),
                    t,
                    sh
                );
            }
        }
        let com = self.center_of_mass(q)?;
        let _ = writeln!(w, "centre of mass ({:.4}, {:.4}) m", com[0], com[1]);
        let d = self.dynamics(q, &vec![0.0; self.dof()])?.mass_matrix;
        let _ = writeln!(
            w,
            "\nD(q) at q = [{}]:",
            q.iter()
                .map(|v| format!("{v:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        for r in 0..d.nrows() {
            let row: Vec<String> = (0..d.ncols())
                .map(|c| format!("{:>8.4}", d[(r, c)]))
                .collect();
            let _ = writeln!(w, "  {}", row.join(" "));
        }
        let eig = d.clone().symmetric_eigenvalues();
        let _ = writeln!(
            w,
            "eigenvalues of D: min {:.3e}, max {:.3e}",
            eig.min(),
            eig.max()
        );
        Ok(s)
    }
}
