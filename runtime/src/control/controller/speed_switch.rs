//! Speed control at the controller's events: the gait a Walk from Stand launches into, and the
//! switch to the regulated library gait at each impact (`runtime::control::speed`).

use super::{walk, Controller, StartBlend, START_BLEND_SPAN};
use crate::control::gait_table::side_index;
use crate::control::speed::SpeedMap;
use crate::slots::{LEG_SLOTS, OUTPUTS};

impl Controller {
    /// Walk from Stand with speed control on a moving belt: the launch and the first step walk
    /// the library gait `speed.launch_gait_fraction` of the way from the Stand gait to the one
    /// that walks the belt's speed (`runtime::control::speed`, "Start and restart").
    pub(super) fn launch_gait(&mut self) {
        let fraction = self.regulator.config().launch_gait_fraction;
        let Some(library) = &self.library else {
            return;
        };
        let s = self.regulator.status;
        if !(fraction > 0.0 && self.regulator.active() && s.belt_mps > 0.0) {
            return;
        }
        let (lo, hi) = library.range_mps();
        let target = library.sigma_for(s.belt_mps + s.offset_mps).clamp(lo, hi);
        let from = if s.library_mps.is_finite() {
            s.library_mps
        } else {
            lo
        };
        let sigma = from + fraction * (target - from);
        library.blend_into(sigma, &mut self.gait, &mut self.lunge, &mut self.step_lever);
        self.orbit.select(sigma);
        self.regulator.status.library_mps = sigma;
    }

    /// At an impact in Walk with speed control on: measures the step that ended, runs the
    /// regulator and, with a library, switches to the gait of the regulated speed, carrying the
    /// references' jump into the new step as a blend (`runtime::control::speed`). Returns the
    /// phase rate to start the new step at; `eval` becomes the new step's first references.
    pub(super) fn switch_speed(
        &mut self,
        step_length_m: f64,
        step_duration_s: f64,
        rate: f64,
        (t, leg_q, leg_dq): (f64, &[f64; LEG_SLOTS], &[f64; LEG_SLOTS]),
        eval: &mut walk::WalkEval,
    ) -> f64 {
        let Some(library) = &self.library else {
            self.regulator
                .on_impact(step_length_m, step_duration_s, (0.0, f64::INFINITY));
            return rate;
        };
        let sigma = self.regulator.on_impact_mapped(
            step_length_m,
            step_duration_s,
            library.range_mps(),
            library,
        );
        let span_old = self.gait.theta_minus_rad - self.gait.theta_plus_rad;
        let mut y_old = eval.y;
        // The step that ended landed its lever's offset from the gait's touchdown pose: relabeled
        // to the new stance leg's outputs, it is part of the jump the new step blends out.
        let (new, old) = (side_index(self.stance), side_index(self.stance.other()));
        for (j, y) in y_old.iter_mut().enumerate() {
            let slot = self.gait.out_slot[new][j];
            if let Some(i) = (0..OUTPUTS).find(|&i| self.gait.out_slot[old][i] == slot) {
                *y += self.step_lever.dy_end(i);
            }
        }
        library.blend_into(sigma, &mut self.gait, &mut self.lunge, &mut self.step_lever);
        self.orbit.select(sigma);
        self.step_lever.offset_m = self.regulator.status.step_offset_m;
        self.step_lever.lean_rad = self.regulator.status.step_lean_rad;
        let span_new = self.gait.theta_minus_rad - self.gait.theta_plus_rad;
        // The same stance-leg angle rate, in the new gait's phase units.
        let rate = if span_new.abs() > 1e-9 {
            rate * span_old / span_new
        } else {
            rate
        };
        *eval = self.walk_references(t, leg_q, leg_dq);
        let mut offset = [0.0; OUTPUTS];
        for (i, o) in offset.iter_mut().enumerate() {
            *o = y_old[i] - eval.y[i];
        }
        self.start_blend = Some(StartBlend {
            from_phase: eval.phase.clamp(0.0, 1.0),
            offset,
            span: START_BLEND_SPAN,
        });
        *eval = self.references(eval.phase, eval.phase_rate, eval.foot_height_m);
        rate
    }
}
