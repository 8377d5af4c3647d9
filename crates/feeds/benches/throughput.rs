//! Feed-schedule throughput (points per second), a plain `main` timing loop.
//!
//!     cargo bench -p thinplan-feeds --bench throughput
//!
//! Times `schedule_polyline` on a ~1 M-point spiral (smooth, curvature everywhere) and a
//! ~1 M-point sharp-cornered zigzag, best of several runs, and prints points/s.

use std::time::Instant;
use thinplan_feeds::{paths, schedule_polyline, MachineLimits};

fn bench(name: &str, pts: &[glam::DVec3], limits: &MachineLimits) {
    let caps = vec![250.0; pts.len() - 1];
    let mut best = f64::INFINITY;
    let mut total = 0.0;
    for _ in 0..7 {
        let t0 = Instant::now();
        let s = schedule_polyline(pts, &caps, limits);
        let dt = t0.elapsed().as_secs_f64();
        total += s.total_time;
        best = best.min(dt);
    }
    println!(
        "{name:<10} {:>9} points  best {:>7.2} ms  {:>6.1} M points/s  (path time {:.3} s)",
        pts.len(),
        best * 1e3,
        pts.len() as f64 / best / 1e6,
        total / 7.0
    );
}

fn main() {
    let limits = MachineLimits::typical_hsm();
    let spiral = paths::spiral(2.0, 400.0, 4.0, 0.25);
    let zigzag = paths::zigzag(1000.0, 1000.0, 4.0, 4.0);
    bench("spiral", &spiral, &limits);
    bench("zigzag", &zigzag, &limits);
}
