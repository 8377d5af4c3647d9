//! Issue-6 diagnosis: why the curvilinear spiral does or does not save time over the offset
//! baseline. For each pocket and L/D: path length, orbits vs rings, the gap between successive
//! turns (min / mean / max over the points of a turn, vs the stepover) and the time split into
//! running at the feed cap vs below it (accelerating, decelerating, curvature-limited), plus
//! the number of full stops.
//!
//! `cargo run --release -p thinplan-pocketing --example diagnose [-- L/D ...]`
use glam::DVec2;
use thinplan_pocketing::bench::{bench_family, bench_params};
use thinplan_pocketing::geom::SegIndex;
use thinplan_pocketing::timing::{time_path, MachineLimits};
use thinplan_pocketing::*;

/// Split the roughing part of a path into turns by winding angle about `c`.
fn turns_about(points: &[DVec2], c: DVec2) -> Vec<Vec<DVec2>> {
    let mut turns: Vec<Vec<DVec2>> = vec![vec![points[0]]];
    let mut acc = 0.0;
    let mut k = 0usize;
    for w in points.windows(2) {
        let (a, b) = (w[0] - c, w[1] - c);
        if a.length_squared() > 1e-18 && b.length_squared() > 1e-18 {
            acc += a.perp_dot(b).atan2(a.dot(b));
        }
        let kk = (acc / std::f64::consts::TAU).floor().max(0.0) as usize;
        if kk > k {
            k = kk;
            turns.push(vec![w[0]]);
        }
        turns.last_mut().unwrap().push(w[1]);
    }
    turns
}

/// Gap statistics (min, mean, max) of the points of each turn to the previous turn.
fn gap_stats(turns: &[Vec<DVec2>]) -> (f64, f64, f64, usize) {
    let (mut mn, mut sum, mut mx, mut n) = (f64::INFINITY, 0.0, 0.0f64, 0usize);
    for w in turns.windows(2) {
        let idx = SegIndex::new(&[&w[0]], false);
        for p in &w[1] {
            let d = idx.nearest(*p);
            mn = mn.min(d);
            mx = mx.max(d);
            sum += d;
            n += 1;
        }
    }
    (mn, sum / n.max(1) as f64, mx, turns.len())
}

/// (time at ≥ 98 % of the cap, time below it, interior full stops, L/V).
fn time_split(points: &[DVec2], feed: f64, lim: &MachineLimits) -> (f64, f64, usize, f64, f64) {
    let s = time_path(points, feed, lim);
    let (mut at_cap, mut below, mut stops) = (0.0, 0.0, 0);
    for i in 0..s.len() - 1 {
        let dt = s.t[i + 1] - s.t[i];
        if s.v[i] >= 0.98 * feed && s.v[i + 1] >= 0.98 * feed {
            at_cap += dt;
        } else {
            below += dt;
        }
        if i > 0 && s.v[i] < 1e-6 {
            stops += 1;
        }
    }
    (at_cap, below, stops, s.length / feed, s.total_time)
}

fn main() {
    let lds: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let lds = if lds.is_empty() {
        vec![1.0, 4.0, 10.0]
    } else {
        lds
    };
    let lim = MachineLimits::typical_hsm();
    let feed = lim.v_max[0];
    let d = lim.accel_distance();
    for &ld in &lds {
        for bp in bench_family(ld * d) {
            if bp.pocket.name != "pentagon" && bp.pocket.name != "isogrid-triangle" {
                continue;
            }
            let params = bench_params(&bp);
            let s = params.stepover;
            let mut paths = vec![(
                "offset-arc".to_string(),
                offset_path(&bp.pocket, &params).unwrap(),
            )];
            paths.push((
                "offset-sharp".into(),
                offset_path_sharp(&bp.pocket, &params).unwrap(),
            ));
            let (m, sm) = offset_path_gap_matched(&bp.pocket, &params).unwrap();
            paths.push((format!("offset-gm {:.2}s", sm / s), m));
            paths.push((
                "curvilinear".into(),
                curvilinear_path(&bp.pocket, &params).unwrap(),
            ));
            let cur = &paths.last().unwrap().1;
            println!(
                "== {} L/D {ld}: L {:.1} mm, tool {:.2}, stepover {:.3} mm; spiral turns {} (bound {:?}), offset rings {}",
                bp.pocket.name,
                bp.pocket.size(),
                params.tool_diameter,
                s,
                cur.roughing_turns(),
                cur.turns_lower_bound(s),
                paths[0].1.roughing_turns()
            );
            for (name, p) in &paths {
                let rough = &p.points[..p.finish_start];
                let (mn, mean, mx, n) = if let Some(c) = p.center {
                    gap_stats(&turns_about(rough, c))
                } else {
                    // offset rings: gaps between successive ring levels (rings sorted innermost
                    // first as in the path)
                    let rings: Vec<Vec<DVec2>> = p.contours.iter().rev().cloned().collect();
                    gap_stats(&rings)
                };
                let (cap, below, stops, lv, tot) = time_split(&p.points, feed, &lim);
                println!(
                    "  {name:<15} {:<15} len {:>7.0} mm | turns {:>3} | gap/s min {:.2} mean {:.2} max {:.2} \
                     | t {:>6.2} s = at cap {:>6.2} + below {:>6.2} (L/V {:.2}, overhead {:>4.0} %) stops {}",
                    p.method.as_str(),
                    p.length(),
                    n,
                    mn / s,
                    mean / s,
                    mx / s,
                    tot,
                    cap,
                    below,
                    lv,
                    100.0 * (tot / lv - 1.0),
                    stops
                );
            }
        }
    }
}
