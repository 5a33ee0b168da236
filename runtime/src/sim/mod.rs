//! The loop on the simulated ADAM: the runner ([`run`]: walks, the soak, walk metrics from
//! ground truth), fault profiles ([`faults`]: wire faults, scheduled and random faults) and
//! their injection into the simulated robot ([`inject`]).

pub mod faults;
pub mod inject;
pub mod run;
