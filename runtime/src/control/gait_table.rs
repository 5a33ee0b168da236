//! The gait as the controller evaluates it: the Bézier outputs y^d(τ), their relabeling to the
//! stance leg's slots and the plan's feed-forward torques, in fixed arrays (no heap).

use crate::config::LEG_JOINT_NAMES;
use crate::slots::{LEG_SLOTS, OUTPUTS};
use crate::{Result, RuntimeError};
use model::bezier::{self, MAX_BEZIER_DEGREE};
use model::gait::{GaitFile, PhaseDefinition, MAX_FEEDFORWARD_SAMPLES};
use model::robot::Legs;
use model::{PlanarModel, Side};

/// The gait as the controller evaluates it: fixed arrays, no heap.
#[derive(Clone, Copy, Debug)]
pub(super) struct GaitTable {
    pub(super) alpha: [[f64; MAX_BEZIER_DEGREE + 1]; OUTPUTS],
    pub(super) alpha_len: usize,
    /// `out_slot[stance][i]`: the leg slot of output i when `stance` (0 left, 1 right) stands.
    pub(super) out_slot: [[usize; OUTPUTS]; 2],
    pub(super) theta_plus_rad: f64,
    pub(super) theta_minus_rad: f64,
    pub(super) step_duration_s: f64,
    pub(super) first_stance: Side,
    /// Planned torso pitch and pitch rate at the start of the step (from `initial_state`).
    pub(super) initial_pitch: Option<(f64, f64)>,
    /// The gait's feed-forward table: phases and torques per output (first `ff_len` rows).
    pub(super) ff_phase: [f64; MAX_FEEDFORWARD_SAMPLES],
    pub(super) ff_torque_nm: [[f64; OUTPUTS]; MAX_FEEDFORWARD_SAMPLES],
    pub(super) ff_len: usize,
}

pub(super) fn side_index(s: Side) -> usize {
    match s {
        Side::Left => 0,
        Side::Right => 1,
    }
}

impl GaitTable {
    pub(super) fn new(gait: &GaitFile, model: &PlanarModel, legs: &Legs) -> Result<Self> {
        if gait.outputs.len() != OUTPUTS {
            return Err(RuntimeError::Gait {
                reason: format!(
                    "{} outputs, the controller drives {OUTPUTS}",
                    gait.outputs.len()
                ),
            });
        }
        let mut out_slot = [[0; OUTPUTS]; 2];
        for stance in [Side::Left, Side::Right] {
            let mut used = [false; LEG_SLOTS];
            for (i, o) in gait.outputs.iter().enumerate() {
                let name = o.joint_name(stance);
                let slot = LEG_JOINT_NAMES
                    .iter()
                    .position(|n| *n == name)
                    .ok_or_else(|| RuntimeError::Gait {
                        reason: format!("output {} drives {name}, not a leg motor", o.name),
                    })?;
                if used[slot] {
                    return Err(RuntimeError::Gait {
                        reason: format!("two outputs drive {name}"),
                    });
                }
                used[slot] = true;
                out_slot[side_index(stance)][i] = slot;
            }
        }
        let (theta_plus_rad, theta_minus_rad) = match gait.phase {
            PhaseDefinition::StateBased {
                theta_plus_rad,
                theta_minus_rad,
            } => (theta_plus_rad, theta_minus_rad),
            // A time-based gait still has a stance-leg angle range; the state-based option
            // needs it, so measure it from the gait's end poses.
            PhaseDefinition::TimeBased => (f64::NAN, f64::NAN),
        };
        let mut alpha = [[0.0; MAX_BEZIER_DEGREE + 1]; OUTPUTS];
        for (i, row) in gait.bezier.alpha.iter().enumerate() {
            alpha[i][..row.len()].copy_from_slice(row);
        }
        let _ = (model, legs);
        let mut ff_phase = [0.0; MAX_FEEDFORWARD_SAMPLES];
        let mut ff_torque_nm = [[0.0; OUTPUTS]; MAX_FEEDFORWARD_SAMPLES];
        let mut ff_len = 0;
        if let Some(ff) = &gait.feedforward {
            // GaitFile::validate bounds the table to MAX_FEEDFORWARD_SAMPLES rows of OUTPUTS.
            for (k, (t, row)) in ff.phase.iter().zip(&ff.torque_nm).enumerate() {
                if k >= MAX_FEEDFORWARD_SAMPLES || row.len() != OUTPUTS {
                    return Err(RuntimeError::Gait {
                        reason: format!("feedforward.torque_nm[{k}] has the wrong shape"),
                    });
                }
                ff_phase[k] = *t;
                ff_torque_nm[k].copy_from_slice(row);
                ff_len = k + 1;
            }
        }
        Ok(Self {
            ff_phase,
            ff_torque_nm,
            ff_len,
            alpha,
            alpha_len: gait.bezier.degree + 1,
            out_slot,
            theta_plus_rad,
            theta_minus_rad,
            step_duration_s: gait.step_duration_s,
            first_stance: gait.stance_leg,
            initial_pitch: gait
                .initial_state
                .as_ref()
                .and_then(|s| Some((*s.q.get(2)?, *s.dq.get(2)?))),
        })
    }

    pub(super) fn eval(&self, i: usize, s: f64) -> (f64, f64) {
        let a = &self.alpha[i][..self.alpha_len];
        (bezier::eval(a, s), bezier::eval_d1(a, s))
    }

    /// The planned torque of each output at phase `s`, N·m (zeros without a table).
    pub(super) fn feedforward(&self, s: f64) -> [f64; OUTPUTS] {
        let mut out = [0.0; OUTPUTS];
        let n = self.ff_len;
        model::gait::interpolate(&self.ff_phase[..n], &self.ff_torque_nm[..n], s, &mut out);
        out
    }
}
