//! # planner: offline HZD gait optimization and co-design for ADAM
//!
//! Stands on [`model`]. Work in progress: the NLP layer (`planner::nlp`) and the
//! collocation problem (`planner::collocation`) arrive with the "Planner I" issue, the
//! co-design of thigh and shin lengths with "Planner II". Nothing here is usable yet.

pub mod nlp;
