//! The loop on the simulated ADAM: the runner ([`run`]: walks, the soak, walk metrics from
//! ground truth) and its fault profiles ([`faults`]: wire faults, scheduled and random faults).

pub mod faults;
pub mod run;
