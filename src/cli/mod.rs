//! The commands of `adam`, one module per group: each holds its clap arguments, the function
//! that calls the libraries, and (in `report`) the `Display` types of what it prints.

pub(crate) mod bench;
pub(crate) mod bringup_target;
pub(crate) mod calibrate;
pub(crate) mod can;
pub(crate) mod codesign;
pub(crate) mod emulate;
pub(crate) mod live;
pub(crate) mod logs;
pub(crate) mod model;
pub(crate) mod op;
pub(crate) mod paths;
pub(crate) mod plan;
pub(crate) mod plots;
pub(crate) mod run;
pub(crate) mod shipped;
pub(crate) mod sweep;
