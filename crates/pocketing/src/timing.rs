//! Timing of pocket paths with the project's feed schedule (`thinplan-feeds`).

use glam::{DVec2, DVec3};
pub use thinplan_feeds::{MachineLimits, Schedule};

/// Time a planar path at constant z with one cutting-feed cap (mm/s).
pub fn time_path(points: &[DVec2], feed: f64, limits: &MachineLimits) -> Schedule {
    let p3: Vec<DVec3> = points.iter().map(|p| DVec3::new(p.x, p.y, 0.0)).collect();
    thinplan_feeds::schedule_polyline_uniform(&p3, feed, limits)
}
