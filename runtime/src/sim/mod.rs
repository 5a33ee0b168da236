//! The loop on the simulated ADAM: the runner ([`run`]: walks, the soak, walk metrics from
//! ground truth), fault profiles ([`faults`]: wire faults, scheduled and random faults) and
//! their injection into the simulated robot ([`inject`]), and what a run is told in time
//! ([`treadmill`]: the belt's speed profile, pushes, scripted operator commands); the report of
//! a run ([`report`]) and the treadmill scenarios of the bench and the acceptance tests
//! ([`scenarios`]), and those scenarios as independent runs of a sweep ([`matrix`]); the robot hung on the boom for bring-up ([`hung`]: calibration, pre-flight,
//! dry run); the simulated robot served over UDP to another process ([`emulate`]).

pub mod emulate;
pub mod faults;
pub mod hung;
pub mod inject;
pub mod matrix;
pub mod report;
pub mod run;
pub mod scenarios;
pub mod treadmill;
