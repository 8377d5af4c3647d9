//! The plan: one serialisable value shared by every stage, the CLI and the GUI.
//!
//! Stages are functions of the plan so far plus knowledge; this crate knows
//! nothing about how stages compute, only what they produce.

pub mod io;
pub mod model;
pub mod order;
pub mod verification;

pub use io::{load, save, PlanIoError};
pub use model::*;
pub use order::topological_order;
pub use verification::*;
