//! The controller: pure, sans-IO logic of one control tick.
//!
//! ```text
//! TickInput { t_s, motor samples[14], IMU sample?, operator command?, overrun streak }
//!   │  motor → model angles (direction, offset)        IMU → PitchEstimator (θ̂, θ̂̇, b̂)
//!   ▼
//! operator command → state machine (Idle → Ramp → Stand → Walk → Stop → Stand … Damping)
//!   ▼
//! SafetyMonitor::check ── trip? ──▶ Damping (latched, reason in Status::trip)
//!   ▼
//! Walk/Stop: q = [0, 0, θ̂, legs…] → θ(q), θ̇ (model::phase) → τ, τ̇ → y^d(τ), ẏ^d = y^d'(τ)·τ̇
//!            swing-foot height + τ ≥ τ_switch, debounced → stance switch (relabel outputs)
//! Ramp: minimum-jerk move from the measured pose to y^d(0); Stand: hold y^d(0)
//! Walk from Stand: ≤ 1 s launch in double support onto the orbit's σ*(θ), then the first step
//!       blends into y^d(τ)
//! Stop: the step under way ends; one braking step (θ⁻ → θ_brake, outputs blended into its
//!       landing pose); 5 ms after its touchdown, Stand holds the landed joint angles, the
//!       landed pose's gravity torques fed forward
//! Walk: no progress of τ for speed.stall_relaunch_s, at rest on both feet ──▶ relaunch from
//!       double support (as Walk from Stand, 0.5 s; once per step; `recovery`)
//! Walk: τ runs back, the swing foot low and speed.step_back_catch_m behind ──▶ set it down
//!       behind, catch from double support, hand over (`recovery`, "The step-back catch")
//! Walk/Stop: no progress of τ for safety.stall_timeout_s ──▶ Damping (Trip::StepTimeout)
//!   ▼
//! TickOutput { commands[14] (PD or damping, motor side), status }
//! ```
//! `tick` never allocates, locks, sleeps or reads a clock: time is `TickInput::t_s`.
//!
//! Motor slots: 0..4 are the leg joints (left hip, left knee, right hip, right knee); 4..14 the
//! held joints of the config, in order. Slots without a motor (fewer held joints, or held
//! motors absent in simulation) have `present == false` in the [`SlotLayout`].
//!
//! # Walk from Stand: a launch
//! At rest in double support the state-based phase has no momentum to run on. On Walk the
//! controller first carries the torso forward with both feet down (1 s: a quintic from rest
//! to 4 cm behind the stance foot, arriving at the speed whose angular momentum about the stance
//! foot is the planned orbit's σ*(θ) there (`orbit_table`; after a Stop: 0.2 m/s);
//! joint targets by `double_support` inverse kinematics, gravity fed forward, PI feedback on
//! the measured torso pose), then lifts the rear foot (after Ramp: as soon as the measured
//! momentum reaches σ*(θ), from 0.9 s on; after a Stop: at 1 s): the first step starts at the
//! measured phase, its outputs blending (minimum jerk) from the launch's end pose into y^d(τ).
//! From there the gait's stable orbit takes over, from the first steps at the planned duration
//! (`runtime/tests/stand_sim.rs`, `restart_sim.rs`).
//!
//! # Stop: why a braking step
//! The gait lands each step with the torso moving at ~0.40 m/s. With point feet, double support
//! can only bring the robot to rest if its capture point `x + ẋ/ω` (ω = √(g/h)) lies between the
//! feet; over a 0.15 m step it lies about 3 cm beyond the front foot, so holding any pose after
//! a normal step vaults the robot over it (measured). The braking step lands the front foot
//! `walk.stop_step_length_m` (0.24 m) ahead instead: the step's stance-leg angle runs on to the
//! braking pose's θ (so τ still ends at 1) and, from τ = 0.3, the outputs blend (minimum jerk)
//! from y^d(τ) into that pose, found by inverse kinematics at start-up
//! (`double_support`: both feet down, the torso where the gait's first pose has it relative to
//! the feet, lowered to keep the legs' reach). The longer landing loses more speed in the
//! impact and leaves the capture point inside the feet; Stand then holds the landed joint
//! angles, with the gravity torques of the landed double-support pose fed forward (both feet
//! loaded: without them the graded-mesh re-plan of the gait rocked on, `double_support`), and
//! the robot rocks from foot to foot a few times and comes to rest
//! (`runtime/tests/stop_sim.rs`). Not longer: Walk again launches from that stance, and from a
//! 0.30 m braking step (feet 0.34 m apart) the launch bent the stance knee until it saturated
//! once the rear foot lifted (`runtime/tests/restart_sim.rs`). With treadmill speed control on
//! a moving belt a Stop may first walk ahead and slow to a gait the braking step stops, and a
//! Walk from Stand may launch onto a faster gait (`runtime::control::speed`, "Start and
//! restart").

use super::double_support::Geometry;
use super::gait_table::{side_index, GaitTable};
use super::orbit::OrbitLever;
use super::recovery::{
    FallingBack, SetDown, StallDetector, CATCH_MAX_FOOT_HEIGHT_M, RELAUNCH,
    RELAUNCH_MAX_PHASE_RATE_PER_S,
};
use super::speed::{SpeedLibrary, SpeedRegulator, StepLever};
use super::tick::{ControlState, JointCommand, OperatorCommand, Status, TickInput, TickOutput};
use super::transitions::{
    braking_touchdown, min_jerk, Launch, Lunge, Ramp, StartBlend, FROM_STAND, MIN_JERK_PEAK_RATE,
    PLANNED_PITCH_SIGMA_RAD, STAND_DELAY_S, START_BLEND_SPAN,
};
use crate::config::{PhaseSource, RuntimeConfig, LEG_JOINT_NAMES};
use crate::estimator::{EstimatorParams, PitchEstimator};
use crate::safety::{ProgressWatch, SafetyInput, SafetyMonitor, Trip};
use crate::slots::{MotorSample, SlotLayout, LEG_SLOTS, OUTPUTS, SLOTS};
use crate::{Result, RuntimeError};
use core::f64::consts::SQRT_2;
use drivers::imu::ImuSample;
use model::gait::GaitFile;
use model::robot::{Legs, MAX_DOF};
use model::{PlanarModel, Side};

mod catch;
mod commands;
mod speed_switch;
#[cfg(test)]
mod tests;
mod walk;

/// The controller. Build once at start-up ([`Controller::new`]); call [`Controller::tick`]
/// every period.
#[derive(Clone, Debug)]
pub struct Controller {
    model: PlanarModel,
    legs: Legs,
    dof: usize,
    q_template: [f64; MAX_DOF],
    leg_coord: [usize; LEG_SLOTS],
    gait: GaitTable,
    layout: SlotLayout,
    phase_source: PhaseSource,
    kp: [f64; LEG_SLOTS],
    kd: [f64; LEG_SLOTS],
    feedforward_nm: [f64; OUTPUTS],
    plan_feedforward_scale: f64,
    damping_kd: f64,
    ramp_min_duration_s: f64,
    ramp_max_speed_rad_s: f64,
    /// The gains ramp's duration after Start, s (`bringup.gains_ramp_s`; 0: none).
    gains_ramp_s: f64,
    /// When the last Start came (the gains ramp counts from it); `None`: gains at full.
    gains_on_t_s: Option<f64>,
    /// The gains ramp's factor of this tick, 0..=1 (1 exactly when no ramp is under way).
    gain_scale: f64,
    switch_min_phase: f64,
    touchdown_height_m: f64,
    touchdown_max_descent_mps: f64,
    touchdown_below_m: f64,
    touchdown_impact_accel_mps2: f64,
    impact_min_phase: f64,
    reference_lead_s: f64,
    touchdown_debounce_ticks: u32,
    max_phase_rate_per_s: f64,
    phase_observer_hz: f64,
    estimator: PitchEstimator,
    accel_while_walking: bool,
    touchdown_pitch_sigma_rad: f64,
    /// IMU samples the encoders' sample lags (`estimator.encoder_lag_samples`).
    encoder_lag_samples: usize,
    touchdown_after_impact: bool,
    /// `estimator.touchdown_gate_rad`.
    touchdown_gate_rad: f64,
    /// The impact's tick measured the legs' pitch: measure it again at the next tick.
    pitch_after_impact_due: bool,
    /// `speed.step_length_after_impact`; and the length measured at the impact's tick, to be
    /// measured again at the next (`runtime::control::speed`, "The step's length").
    step_length_after_impact: bool,
    step_length_due_m: Option<f64>,
    safety: SafetyMonitor,
    // Run-time state.
    state: ControlState,
    stance: Side,
    steps: u32,
    step_start_t_s: f64,
    /// The step timeout: trips [`Trip::StepTimeout`] when the walk's phase stops progressing.
    progress: ProgressWatch,
    /// The stall relaunch's detector (`runtime::control::recovery`).
    stall: StallDetector,
    /// Relaunches after a stalled step since start-up.
    recoveries: u32,
    /// `speed.step_back_catch_m` (0: off), the step-back catches since start-up, whether the
    /// step's phase runs back, and the swing foot being set down (`runtime::control::recovery`).
    step_back_catch_m: f64,
    catches: u32,
    catch_watch: FallingBack,
    set_down: Option<SetDown>,
    touchdown_ticks: u32,
    /// (time, swing-foot height) at the previous walking tick.
    last_foot: Option<(f64, f64)>,
    /// Phase observer state: (τ̂, τ̂̇, time of the last update) once walking.
    phase_hat: Option<(f64, f64, f64)>,
    ramp: Ramp,
    /// Stand after a Stop holds these leg joint angles, model rad (`None`: Stand holds the
    /// gait's first pose, as after Ramp).
    stand_hold: Option<[f64; LEG_SLOTS]>,
    /// ... with the gravity torques of the landed pose fed forward, N·m (model side).
    stand_ff_nm: [f64; LEG_SLOTS],
    /// When the braking step of a Stop touched down (Stand starts [`STAND_DELAY_S`] later).
    stop_touchdown_t_s: Option<f64>,
    /// The braking step of a Stop: its touchdown pose and stance-leg angle.
    lunge: Lunge,
    /// The current step is the braking step.
    braking: bool,
    /// Walk was asked for in Stand: the launch starts at this tick.
    launch_requested: bool,
    launch: Option<Launch>,
    start_blend: Option<StartBlend>,
    /// Longest hip-to-foot distance the legs reach (thigh + shin), m.
    leg_reach_m: f64,
    trip: Option<Trip>,
    motors: [MotorSample; SLOTS],
    last_imu_t_s: Option<f64>,
    /// The gait library by speed (`None`: the one gait, no switching).
    library: Option<SpeedLibrary>,
    /// The step-to-step speed regulator and the belt-position loop.
    regulator: SpeedRegulator,
    /// The step-length lever of the gait walked, and this step's offset (speed control).
    step_lever: StepLever,
    /// The within-step orbit lever (`runtime::control::orbit`).
    orbit: OrbitLever,
}

impl Controller {
    /// A controller for `gait` on `model` with `config`; `with_held` = whether the held
    /// motors are driven (false in simulations without them). Allocates; call at start-up.
    pub fn new(
        config: &RuntimeConfig,
        gait: &GaitFile,
        model: PlanarModel,
        with_held: bool,
    ) -> Result<Self> {
        Self::with_library(config, gait, &[], model, with_held)
    }

    /// [`Controller::new`] with a gait library (gaits sorted by `speed_mps`, at least two; empty:
    /// none): once the operator sets a belt speed, each impact switches to the library's gait
    /// for the regulated speed (`runtime::control::speed`). `gait` is walked until then.
    pub fn with_library(
        config: &RuntimeConfig,
        gait: &GaitFile,
        library: &[GaitFile],
        model: PlanarModel,
        with_held: bool,
    ) -> Result<Self> {
        config.validate("runtime config")?;
        model.check_capacity()?;
        let legs = model.legs()?;
        let dof = model.dof();
        let nominal = model.nominal_pose()?;
        let q = model.with_design(
            &nominal,
            gait.design.thigh_length_m,
            gait.design.shin_length_m,
        )?;
        let mut q_template = [0.0; MAX_DOF];
        q_template[..dof].copy_from_slice(&q);
        q_template[0] = 0.0;
        q_template[1] = 0.0;
        let mut leg_coord = [0; LEG_SLOTS];
        for (k, name) in LEG_JOINT_NAMES.iter().enumerate() {
            leg_coord[k] = model.joints[model.require_joint(name)?].coordinate;
        }
        let gait_table = GaitTable::new(gait, &model, &legs)?;
        if config.walk.phase == PhaseSource::StateBased && !gait_table.theta_plus_rad.is_finite() {
            return Err(RuntimeError::Gait {
                reason: "walk.phase = state_based needs a state-based gait (θ⁺, θ⁻)".into(),
            });
        }
        if config.gains.plan_feedforward_scale > 0.0 && gait_table.ff_len == 0 {
            return Err(RuntimeError::Gait {
                reason: format!(
                    "gains.plan_feedforward_scale = {} but the gait file has no feedforward \
                     table: re-plan it with `adam plan`, or set the scale to 0 (PD only)",
                    config.gains.plan_feedforward_scale
                ),
            });
        }
        let geometry = Geometry {
            model: &model,
            legs: &legs,
            dof,
            q_template: &q_template,
            leg_coord: &leg_coord,
        };
        let stop_step_m = config.walk.stop_step_length_m;
        let lunge = braking_touchdown(&geometry, &gait_table, stop_step_m).ok_or_else(|| {
            RuntimeError::InvalidField {
                origin: "runtime config".into(),
                field: "walk.stop_step_length_m".into(),
                value: stop_step_m.to_string(),
                reason: format!(
                    "the braking step's touchdown pose is out of the legs' reach \
                         (thigh {:.3} m, shin {:.3} m)",
                    gait.design.thigh_length_m, gait.design.shin_length_m
                ),
            }
        })?;
        let step_lever =
            StepLever::of(&geometry, &gait_table, gait.step_length_m).unwrap_or_default();
        let orbit = OrbitLever::new(&config.orbit, &geometry, (gait, &gait_table), library)?;
        let library = SpeedLibrary::new(
            library,
            (gait, &gait_table),
            &model,
            &legs,
            &geometry,
            (stop_step_m, &config.speed),
        )?;
        let layout = SlotLayout::new(config, with_held);
        let zero_ramp = Ramp {
            start_t_s: 0.0,
            duration_s: 0.0,
            from: [0.0; SLOTS],
            to: [0.0; SLOTS],
        };
        Ok(Self {
            legs,
            dof,
            q_template,
            leg_coord,
            gait: gait_table,
            layout,
            phase_source: config.walk.phase,
            kp: config.gains.kp_nm_per_rad,
            kd: config.gains.kd_nm_s_per_rad,
            feedforward_nm: config.gains.walk_feedforward_nm,
            plan_feedforward_scale: config.gains.plan_feedforward_scale,
            damping_kd: config.gains.damping_kd_nm_s_per_rad,
            ramp_min_duration_s: config.ramp.min_duration_s,
            ramp_max_speed_rad_s: config.ramp.max_speed_rad_s,
            gains_ramp_s: config.bringup.gains_ramp_s,
            gains_on_t_s: None,
            gain_scale: 1.0,
            switch_min_phase: config.walk.switch_min_phase,
            touchdown_height_m: config.walk.touchdown_height_m,
            touchdown_max_descent_mps: config.walk.touchdown_max_descent_mps,
            touchdown_below_m: config.walk.touchdown_below_m,
            touchdown_impact_accel_mps2: config.walk.touchdown_impact_accel_mps2,
            impact_min_phase: config.walk.impact_min_phase,
            reference_lead_s: config.walk.reference_lead_s,
            touchdown_debounce_ticks: config.walk.touchdown_debounce_ticks,
            max_phase_rate_per_s: config.walk.max_phase_rate_per_s,
            phase_observer_hz: config.walk.phase_observer_hz,
            estimator: PitchEstimator::new(EstimatorParams::from(&config.estimator)),
            accel_while_walking: config.estimator.accel_while_walking,
            touchdown_pitch_sigma_rad: config.estimator.touchdown_pitch_sigma_rad,
            encoder_lag_samples: config.estimator.encoder_lag_samples as usize,
            touchdown_after_impact: config.estimator.touchdown_after_impact,
            touchdown_gate_rad: config.estimator.touchdown_gate_rad,
            pitch_after_impact_due: false,
            step_length_after_impact: config.speed.step_length_after_impact,
            step_length_due_m: None,
            safety: SafetyMonitor::new(
                config.safety.clone(),
                config.loop_.max_overrun_streak,
                layout,
            ),
            state: ControlState::Idle,
            stance: gait.stance_leg,
            steps: 0,
            step_start_t_s: 0.0,
            progress: ProgressWatch::new(config.safety.stall_timeout_s),
            stall: StallDetector::new(config.speed.stall_relaunch_s),
            recoveries: 0,
            step_back_catch_m: config.speed.step_back_catch_m,
            catches: 0,
            catch_watch: FallingBack::default(),
            set_down: None,
            touchdown_ticks: 0,
            last_foot: None,
            phase_hat: None,
            ramp: zero_ramp,
            stand_hold: None,
            stand_ff_nm: [0.0; LEG_SLOTS],
            stop_touchdown_t_s: None,
            lunge,
            braking: false,
            launch_requested: false,
            launch: None,
            start_blend: None,
            leg_reach_m: gait.design.thigh_length_m + gait.design.shin_length_m,
            trip: None,
            motors: [MotorSample::default(); SLOTS],
            last_imu_t_s: None,
            library,
            regulator: SpeedRegulator::new(&config.speed, gait.speed_mps),
            step_lever,
            orbit,
            model,
        })
    }

    /// Current state.
    pub fn state(&self) -> ControlState {
        self.state
    }

    /// Slot layout.
    pub fn layout(&self) -> &SlotLayout {
        &self.layout
    }

    /// Current stance leg.
    pub fn stance(&self) -> Side {
        self.stance
    }

    /// The latched trip, if any.
    pub fn trip(&self) -> Option<Trip> {
        self.trip
    }

    /// Enter Walk at `t_s` with the gait's first stance leg, as if the previous step had just
    /// ended: for a backend that starts in the gait's planned post-impact state (a simulator set
    /// to the gait file's `initial_state`), where Ramp and Stand would have no meaning. The pitch
    /// estimator starts from the planned pitch: mid-step, the accelerometer does not see gravity
    /// alone. Only from Idle with no latched trip; returns whether Walk was entered.
    pub fn begin_walk_at_step_start(&mut self, t_s: f64, status: &mut Status) -> bool {
        if self.state != ControlState::Idle || self.trip.is_some() {
            return false;
        }
        if let Some((pitch_rad, rate_rad_s)) = self.gait.initial_pitch {
            self.estimator
                .initialize(pitch_rad, rate_rad_s, PLANNED_PITCH_SIGMA_RAD);
        }
        self.stance = self.gait.first_stance;
        self.step_start_t_s = t_s;
        self.touchdown_ticks = 0;
        self.last_foot = None;
        self.phase_hat = None;
        self.steps = 0;
        match &self.library {
            Some(library) => {
                let sigma = self.regulator.status.library_mps;
                self.regulator.restart_on(sigma, library);
            }
            None => self.regulator.restart(),
        }
        self.step_lever.rest();
        // As after an impact: a stall of this first step may relaunch, or a catch follow.
        self.stall.restart(t_s, f64::NAN);
        self.restart_catch();
        self.enter(ControlState::Walk, status);
        true
    }

    /// The gait's first pose by slot (motor side for every slot), as Ramp targets it.
    pub fn first_pose(&self) -> [f64; SLOTS] {
        self.stand_pose(self.gait.first_stance)
    }

    fn stand_pose(&self, stance: Side) -> [f64; SLOTS] {
        let mut pose = self.layout.held_center_rad;
        for i in 0..OUTPUTS {
            let slot = self.gait.out_slot[side_index(stance)][i];
            let (y, _) = self.gait.eval(i, 0.0);
            pose[slot] = self.to_motor(slot, y);
        }
        pose
    }

    fn to_motor(&self, slot: usize, model_rad: f64) -> f64 {
        self.layout.motor_rad(slot, model_rad)
    }

    fn to_model(&self, slot: usize, motor_rad: f64) -> f64 {
        self.layout.model_rad(slot, motor_rad)
    }

    fn enter(&mut self, to: ControlState, status: &mut Status) {
        if to != self.state {
            status.transition = Some((self.state, to));
            self.state = to;
        }
    }

    fn begin_ramp(&mut self, t_s: f64) {
        let to = self.stand_pose(self.stance);
        let mut from = to;
        let mut largest = 0.0_f64;
        for slot in 0..SLOTS {
            if self.layout.present[slot] {
                from[slot] = self.motors[slot].q_rad;
                largest = largest.max((to[slot] - from[slot]).abs());
            }
        }
        // Minimum-jerk peak speed is 1.875·Δq/T: lengthen T to respect the speed limit.
        let duration_s = self
            .ramp_min_duration_s
            .max(MIN_JERK_PEAK_RATE * largest / self.ramp_max_speed_rad_s);
        self.ramp = Ramp {
            start_t_s: t_s,
            duration_s,
            from,
            to,
        };
    }

    fn handle_operator(&mut self, cmd: OperatorCommand, t_s: f64, status: &mut Status) {
        use ControlState as S;
        match (cmd, self.state) {
            (OperatorCommand::EStop, _) => {
                if self.trip.is_none() {
                    self.trip = Some(Trip::EStop);
                    status.new_trip = true;
                }
                self.enter(S::Damping, status);
            }
            (OperatorCommand::Damp, _) => self.enter(S::Damping, status),
            (OperatorCommand::Start, S::Idle) => {
                self.gains_on_t_s = Some(t_s);
                self.regulator.at_start();
                self.stance = self.gait.first_stance;
                self.stand_hold = None;
                self.begin_ramp(t_s);
                self.enter(S::Ramp, status);
            }
            (OperatorCommand::Walk, S::Stand) => {
                self.step_start_t_s = t_s;
                self.touchdown_ticks = 0;
                self.steps = 0;
                self.regulator.restart_from_stand();
                self.step_lever.rest();
                self.launch_gait();
                self.launch_requested = true;
                self.enter(S::Walk, status);
            }
            (OperatorCommand::Stop, S::Walk) => {
                self.stop_touchdown_t_s = None;
                self.braking = false;
                if self.library.is_some() && self.regulator.active() {
                    self.regulator.begin_stop();
                }
                self.enter(S::Stop, status);
            }
            (OperatorCommand::Reset, S::Damping) => {
                self.trip = None;
                self.safety.reset_counters();
                self.enter(S::Idle, status);
            }
            _ => {} // not meaningful in this state: ignored
        }
    }

    /// One control tick. Never allocates, locks, sleeps or reads a clock.
    pub fn tick(&mut self, input: &TickInput, out: &mut TickOutput) {
        let t = input.t_s;
        let status = &mut out.status;
        status.transition = None;
        status.new_trip = false;
        // Motors: keep the last known values of silent ones.
        for slot in 0..SLOTS {
            let m = input.motors[slot];
            if m.fresh {
                self.motors[slot] = m;
            } else {
                self.motors[slot].fresh = false;
            }
        }
        let mut leg_q = [0.0; LEG_SLOTS];
        let mut leg_dq = [0.0; LEG_SLOTS];
        for k in 0..LEG_SLOTS {
            leg_q[k] = self.to_model(k, self.motors[k].q_rad);
            leg_dq[k] = self.layout.model_rate_rad_s(k, self.motors[k].dq_rad_s);
        }
        // Estimator.
        // An implausible sample (a glitch; safety counts them) is not integrated, nor is a sample
        // already integrated: an IMU slower than the loop (a VN-100 at 800 Hz under a 1 kHz loop)
        // hands the same sample, with its own time stamp, to the next tick too.
        let already_used = |i: &ImuSample| self.last_imu_t_s == Some(i.t_s);
        if let Some(imu) = input
            .imu
            .as_ref()
            .filter(|i| self.safety.gyro_plausible(i) && !already_used(i))
        {
            let dt = self.last_imu_t_s.map_or(0.0, |t0| imu.t_s - t0);
            let walking = matches!(self.state, ControlState::Walk | ControlState::Stop);
            self.estimator.update_with(
                imu.gyro_pitch_rad_s,
                imu.accel_x_mps2,
                imu.accel_z_mps2,
                dt,
                !walking || self.accel_while_walking,
            );
            self.last_imu_t_s = Some(imu.t_s);
        }
        // Standing after Ramp on a treadmill (the operator gave its belt speed) both feet are on
        // the belt: the legs measure the pitch (the one that levels the feet, as at a
        // touchdown), which the belt's acceleration does not bias as it tilts the
        // accelerometer's gravity (`runtime::estimator`). Compared with the latest estimate,
        // whatever `estimator.encoder_lag_samples` says, a choice by measurement: with the lag
        // on here too, a walk from Stand onto a belt at 0.25 m/s launched 0.8 s later and ran
        // off the back of the belt in seed 4 (`adam bench treadmill`, table (d); the launch was
        // tuned with this measurement unlagged). Why is open: on a still robot with a constant
        // gyro bias the two converge alike (from 50 ms on, pitch within 7e-7 rad and bias
        // within 2.6e-5 rad/s of each other: `runtime::estimator`'s tests), so the difference
        // comes from the Stand on the moving belt, whose ramp rocks the robot.
        if self.state == ControlState::Stand && self.stand_hold.is_none() && self.regulator.active()
        {
            self.measure_legs_pitch(&leg_q, self.touchdown_pitch_sigma_rad, 0, 0.0);
        }
        // The tick after an impact: the legs' pitch again, the new stance foot down, the old
        // one just lifting (its error has the other sign of the impact tick's).
        if std::mem::take(&mut self.pitch_after_impact_due)
            && matches!(self.state, ControlState::Walk | ControlState::Stop)
        {
            self.measure_legs_pitch(
                &leg_q,
                self.touchdown_pitch_sigma_rad * SQRT_2,
                self.encoder_lag_samples,
                self.touchdown_gate_rad,
            );
        }
        // The tick after an impact: the step's length again, both feet down.
        if let Some(at_impact_m) = self.step_length_due_m.take() {
            let length_m = -self.feet_offset_at(self.estimator.pitch_rad(), &leg_q)[0];
            self.regulator.correct_step_length(length_m - at_impact_m);
        }
        // Operator, then safety (a trip overrides any request).
        if let Some(cmd) = input.operator {
            if !self
                .regulator
                .operator(cmd, self.state == ControlState::Walk)
            {
                self.handle_operator(cmd, t, status);
            }
        }
        self.regulator.advance(t);
        let mut speed_update = false;
        let safety_in = SafetyInput {
            t_s: t,
            motors: &self.motors,
            leg_q_rad: &leg_q,
            imu: input.imu.as_ref(),
            pitch_rad: self.estimator.pitch_rad(),
            overrun_streak: input.overrun_streak,
        };
        if let Some(trip) = self.safety.check(&safety_in, self.state.is_driven()) {
            if self.trip.is_none() {
                self.trip = Some(trip);
                status.new_trip = true;
            }
            self.enter(ControlState::Damping, status);
        }
        if self.state == ControlState::Ramp && t - self.ramp.start_t_s >= self.ramp.duration_s {
            self.enter(ControlState::Stand, status);
        }

        // The gains ramp in after Start (linearly; exactly 1 once done or without a ramp).
        self.gain_scale = match self.gains_on_t_s {
            Some(t0) if self.gains_ramp_s > 0.0 && t - t0 < self.gains_ramp_s => {
                ((t - t0) / self.gains_ramp_s).clamp(0.0, 1.0)
            }
            _ => 1.0,
        };

        // Commands.
        let mut y_des = [0.0; OUTPUTS];
        let mut dy_des = [0.0; OUTPUTS];
        let (mut phase, mut phase_rate, mut foot_h) = (0.0, 0.0, f64::NAN);
        match self.state {
            ControlState::Idle | ControlState::Damping => {
                out.commands = [JointCommand::damping(self.damping_kd); SLOTS];
            }
            ControlState::Ramp => {
                let r = self.ramp;
                let u = if r.duration_s > 0.0 {
                    (t - r.start_t_s) / r.duration_s
                } else {
                    1.0
                };
                let (s, ds_du) = min_jerk(u);
                let du_dt = if r.duration_s > 0.0 {
                    1.0 / r.duration_s
                } else {
                    0.0
                };
                for slot in 0..SLOTS {
                    let dq = r.to[slot] - r.from[slot];
                    out.commands[slot] =
                        self.pd(slot, r.from[slot] + s * dq, dq * ds_du * du_dt, 0.0);
                }
            }
            ControlState::Stand => self.stand_commands(&mut out.commands),
            ControlState::Walk if self.launch_requested || self.launch.is_some() => {
                if self.launch_requested {
                    self.launch_requested = false;
                    self.begin_launch(t, FROM_STAND, &leg_q, &leg_dq);
                }
                if self
                    .launch
                    .is_some_and(|l| t - l.start_t_s < l.timing.duration_s)
                    && !self.launch_on_orbit(t, &leg_q, &leg_dq)
                {
                    self.launch_commands(t, &leg_q, &leg_dq, &mut out.commands);
                    // The phase is reported (the stance-leg angle), not yet used.
                    let eval = self.walk_references(t, &leg_q, &leg_dq);
                    (phase, phase_rate, foot_h) = (eval.phase, eval.phase_rate, eval.foot_height_m);
                } else {
                    let eval = self.walk_references(t, &leg_q, &leg_dq);
                    let stance = side_index(self.stance);
                    let mut offset = [0.0; OUTPUTS];
                    for (i, o) in offset.iter_mut().enumerate() {
                        *o = leg_q[self.gait.out_slot[stance][i]] - eval.y[i];
                    }
                    self.start_blend = Some(StartBlend::new(eval.phase.clamp(0.0, 1.0), offset));
                    // The first step starts now (a time-based phase counts from here; the step
                    // timeout watches its phase from the next tick).
                    self.step_start_t_s = t;
                    // After a catch the step may stall or run back again, like any step.
                    if self.launch.is_some_and(|l| l.catch.is_some()) {
                        self.stall.restart(t, eval.phase);
                        self.restart_catch();
                    }
                    self.launch = None;
                    self.last_foot = None;
                    // The same measured phase, now with the blend.
                    let eval = self.references(eval.phase, eval.phase_rate, eval.foot_height_m);
                    (y_des, dy_des) = (eval.y, eval.dy);
                    (phase, phase_rate, foot_h) = (eval.phase, eval.phase_rate, eval.foot_height_m);
                    self.walk_commands(&eval, &mut out.commands);
                }
            }
            ControlState::Walk | ControlState::Stop => {
                let mut eval = self.walk_references(t, &leg_q, &leg_dq);
                self.observe_phase(t, &mut eval);
                // The foot is down once it stops descending near the ground (a kinematic
                // height alone would switch millimetres early, before the impact).
                let descent_mps = match self.last_foot {
                    Some((t0, h0)) if t > t0 => (h0 - eval.foot_height_m) / (t - t0),
                    _ => f64::INFINITY,
                };
                self.last_foot = Some((t, eval.foot_height_m));
                // The impact itself: a spike of the accelerometer (the IMU averages over its
                // sample period, so the impulse shows in one sample).
                let impact = input.imu.as_ref().is_some_and(|imu| {
                    (imu.accel_x_mps2.hypot(imu.accel_z_mps2) - crate::estimator::GRAVITY_MPS2)
                        .abs()
                        >= self.touchdown_impact_accel_mps2
                });
                // The impact spike late in the step, with the swing foot near the ground, is the
                // touchdown, even a little before τ = 1 (the feet are both down only then: the
                // pitch that levels them is measured at this very sample).
                let near = eval.foot_height_m <= self.touchdown_height_m;
                let impact_switch = impact && near && eval.phase >= self.impact_min_phase;
                // Without a spike: τ ≥ τ_switch and the foot stopped descending, or lies below
                // the stance foot (the old stance foot lifting off after the impact), debounced.
                let landed = descent_mps <= self.touchdown_max_descent_mps
                    || eval.foot_height_m <= -self.touchdown_below_m;
                if eval.touchdown && landed {
                    self.touchdown_ticks += 1;
                } else {
                    self.touchdown_ticks = 0;
                }
                if impact_switch || self.touchdown_ticks >= self.touchdown_debounce_ticks {
                    if impact_switch {
                        // Halved in weight if the next tick measures again.
                        let twice = if self.touchdown_after_impact {
                            SQRT_2
                        } else {
                            1.0
                        };
                        self.measure_legs_pitch(
                            &leg_q,
                            self.touchdown_pitch_sigma_rad * twice,
                            self.encoder_lag_samples,
                            self.touchdown_gate_rad,
                        );
                        self.pitch_after_impact_due = self.touchdown_after_impact;
                    }
                    // The step that ends: its length (feet at the impact) and duration.
                    let step_length_m = self.feet_offset_at(self.estimator.pitch_rad(), &leg_q)[0];
                    let step_duration_s = t - self.step_start_t_s;
                    // Impact: relabel the legs and start the next step.
                    self.stance = self.stance.other();
                    self.start_blend = None;
                    self.step_start_t_s = t;
                    self.touchdown_ticks = 0;
                    self.last_foot = None;
                    self.steps = self.steps.saturating_add(1);
                    // Stop: the step under way ends, then the braking step, then Stand (with
                    // speed control, the Stop's approach and slowing steps first).
                    // (`stopping` only after `begin_stop`, which needs a library and a belt.)
                    let approach = self.state == ControlState::Stop
                        && !self.braking
                        && self.stop_touchdown_t_s.is_none()
                        && self.regulator.stopping();
                    if self.state == ControlState::Stop && !approach {
                        if self.braking {
                            self.stop_touchdown_t_s = Some(t);
                        }
                        self.braking = !self.braking;
                    }
                    // The new step starts at the measured phase, at the speed of the old one.
                    let mut rate = self.phase_hat.map_or(0.0, |(_, r, _)| r);
                    eval = self.walk_references(t, &leg_q, &leg_dq);
                    if (self.state == ControlState::Walk || approach) && self.regulator.active() {
                        speed_update = true;
                        rate = self.switch_speed(
                            step_length_m,
                            step_duration_s,
                            rate,
                            (t, &leg_q, &leg_dq),
                            &mut eval,
                        );
                        // The encoders sampled the feet before the impact the IMU felt.
                        let again = impact_switch && self.step_length_after_impact;
                        self.step_length_due_m = again.then_some(step_length_m);
                        if approach && self.regulator.brake_now() {
                            self.braking = true;
                            eval = self.walk_references(t, &leg_q, &leg_dq);
                        }
                    }
                    self.phase_hat = Some((eval.phase, rate, t));
                    self.observe_phase(t, &mut eval);
                    self.progress.restart(t, eval.phase);
                    self.stall.restart(t, eval.phase);
                    self.restart_catch();
                }
                // A Walk step stalled, the robot nearly at rest on both feet (the swing foot
                // landed at the stance foot's height): relaunch from double support
                // (`recovery`); the launch's commands start with the next tick.
                let at_rest_on_both_feet = eval.foot_height_m.abs() <= self.touchdown_height_m
                    && landed
                    && eval.phase_rate.abs() <= RELAUNCH_MAX_PHASE_RATE_PER_S;
                if self.state == ControlState::Walk
                    && !self.braking
                    && self.stall.check(t, eval.phase, at_rest_on_both_feet)
                {
                    self.begin_launch(t, RELAUNCH, &leg_q, &leg_dq);
                    if self.launch.is_some() {
                        self.recoveries = self.recoveries.saturating_add(1);
                    }
                }
                // The phase runs back, the swing foot low and behind the stance foot: the
                // step-back catch (`recovery`) sets it down at once.
                if self.state == ControlState::Walk
                    && !self.braking
                    && self.launch.is_none()
                    && self.step_back_catch_m > 0.0
                    && eval.foot_height_m <= CATCH_MAX_FOOT_HEIGHT_M
                    && self.set_down.is_none()
                    && self
                        .catch_watch
                        .falling_back(t, eval.phase, eval.phase_rate)
                {
                    self.begin_set_down(t, &leg_q, &leg_dq);
                }
                (y_des, dy_des) = (eval.y, eval.dy);
                (phase, phase_rate, foot_h) = (eval.phase, eval.phase_rate, eval.foot_height_m);
                // The braking step has landed: once the motors report the post-impact pose (the
                // replies lag the impact by a tick), Stand holds it.
                if self.state == ControlState::Stop
                    && self
                        .stop_touchdown_t_s
                        .is_some_and(|t0| t - t0 >= STAND_DELAY_S - 1e-9)
                {
                    self.stand_hold = Some(leg_q);
                    self.stand_ff_nm = self.stand_gravity_torques(&leg_q, &leg_dq);
                    self.enter(ControlState::Stand, status);
                }
                if self.state == ControlState::Stand {
                    self.stand_commands(&mut out.commands);
                } else {
                    self.lean(t, &leg_q, &leg_dq, &mut eval);
                    self.set_down_outputs(t, &leg_q, &leg_dq, &mut eval);
                    (y_des, dy_des) = (eval.y, eval.dy);
                    self.walk_commands(&eval, &mut out.commands);
                }
            }
        }
        // The step timeout: a walk whose phase stopped progressing (held, stuck on both feet).
        let walking = matches!(self.state, ControlState::Walk | ControlState::Stop);
        if self.state != ControlState::Walk || self.launch.is_some() {
            self.stall.disarm();
        }
        if !walking || self.launch.is_some() {
            self.progress.disarm();
        } else if !self.progress.armed() {
            self.progress.restart(t, phase);
        } else if let Some(trip) = self.progress.check(t, phase) {
            if self.trip.is_none() {
                self.trip = Some(trip);
                status.new_trip = true;
            }
            self.enter(ControlState::Damping, status);
            out.commands = [JointCommand::damping(self.damping_kd); SLOTS];
            (y_des, dy_des) = ([0.0; OUTPUTS], [0.0; OUTPUTS]);
        }
        let stance = side_index(self.stance);
        let mut y_act = [0.0; OUTPUTS];
        for (i, y) in y_act.iter_mut().enumerate() {
            *y = leg_q[self.gait.out_slot[stance][i]];
        }
        *status = Status {
            state: self.state,
            transition: status.transition,
            stance: self.stance,
            steps: self.steps,
            recoveries: self.recoveries,
            catches: self.catches,
            phase,
            phase_rate_per_s: phase_rate,
            y_des_rad: y_des,
            dy_des_rad_s: dy_des,
            y_act_rad: y_act,
            swing_foot_height_m: foot_h,
            pitch_rad: self.estimator.pitch_rad(),
            pitch_rate_rad_s: self.estimator.pitch_rate_rad_s(),
            gyro_bias_rad_s: self.estimator.gyro_bias_rad_s(),
            trip: self.trip,
            new_trip: status.new_trip,
            leg_q_rad: leg_q,
            speed: self.regulator.status,
            speed_update,
        };
    }
}
