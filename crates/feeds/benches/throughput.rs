//! Feed-schedule throughput (points per second), a plain `main` timing loop.
//!
//!     cargo bench -p thinplan-feeds --bench throughput
//!
//! Times `schedule_polyline` (release) on ~1 M-point paths: a spiral (curvature everywhere),
//! a sharp-cornered zigzag and a zigzag with rounded turns. Prints the best wall-clock time of
//! several runs and, on Linux, the CPU time of this thread (which the machine's other load
//! does not inflate as much).

use std::time::Instant;
use thinplan_feeds::{paths, schedule_polyline, MachineLimits};

/// CPU time of this thread (s) from /proc, if available (10 ms ticks).
fn thread_cpu() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn bench(name: &str, pts: &[glam::DVec3], limits: &MachineLimits) {
    let caps = vec![250.0; pts.len() - 1];
    let runs = 10;
    let mut best = f64::INFINITY;
    let mut path_time = 0.0;
    let cpu0 = thread_cpu();
    for _ in 0..runs {
        let t0 = Instant::now();
        let s = schedule_polyline(pts, &caps, limits);
        best = best.min(t0.elapsed().as_secs_f64());
        path_time = s.total_time;
    }
    let cpu = cpu0.zip(thread_cpu()).map(|(a, b)| (b - a) / runs as f64);
    let n = pts.len() as f64;
    print!(
        "{name:<10} {:>8} points  best wall {:>7.1} ms = {:>5.1} M points/s",
        pts.len(),
        best * 1e3,
        n / best / 1e6
    );
    match cpu {
        Some(c) if c > 0.0 => print!(
            "  mean CPU {:>7.1} ms = {:>5.1} M points/s",
            c * 1e3,
            n / c / 1e6
        ),
        _ => {}
    }
    println!("  (path time {path_time:.1} s)");
}

fn main() {
    let limits = MachineLimits::typical_hsm();
    bench("spiral", &paths::spiral(2.0, 400.0, 2.0, 0.25), &limits);
    bench("zigzag", &paths::zigzag(1000.0, 1000.0, 4.0, 0.25), &limits);
    bench(
        "zigzag-r",
        &paths::zigzag_rounded(1000.0, 1000.0, 4.0, 0.25),
        &limits,
    );
}
