//! Knowledge for stage 2, recognition: what counts as a wall, a hole, a
//! pocket … Thresholds and priorities, never code.

mod depressions;
mod walls;

pub use depressions::*;
pub use walls::*;
