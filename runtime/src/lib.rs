//! # runtime: real-time execution of an HZD gait on ADAM
//!
//! Stands on [`drivers`]. Work in progress: the control loop, estimator, safety monitor,
//! telemetry and MCAP logging arrive with the "Runtime" issue. Nothing here is usable yet.
