//! Compare our feed schedule with TOPP-RA (tools/peers/toppra) on smooth test paths.
//!
//!     bash tools/peers/toppra/setup.sh      # once: toppra into $HOME/.cache/thinplan-venv
//!     cargo run --release -p thinplan-feeds --example toppra_compare [-- SCRIPT_ARGS...]
//!
//! SCRIPT_ARGS go to toppra_time.py, e.g. `--grid-factor 16` or `--scheme interpolation`.
//!
//! What is compared: the same points, the same per-axis velocity and acceleration limits,
//! rest to rest. Our centripetal cap is disabled (infinite) and the feed caps are out of
//! reach (1e6 mm/s), because TOPP-RA has neither; no path has a corner (every turning angle
//! is far below 30°, which the example checks), because TOPP-RA has no corner stops.
//! TOPP-RA's path is a cubic spline through the points parameterised by chord length (see
//! toppra_time.py); ours is the polyline with three-point curvature. The paths JSON is
//! written to `$CARGO_TARGET_DIR/toppra_paths.json` (or the system temp dir).

use glam::DVec3;
use std::path::PathBuf;
use std::process::Command;
use thinplan_feeds::{paths, schedule_polyline_uniform, MachineLimits};

fn max_turn_deg(p: &[DVec3]) -> f64 {
    p.windows(3)
        .map(|w| (w[1] - w[0]).angle_between(w[2] - w[1]).to_degrees())
        .fold(0.0, f64::max)
}

fn main() {
    let script_args: Vec<String> = std::env::args().skip(1).collect();
    // A machine with a slower Z, so the helix exercises per-axis limits in 3D.
    let limits = MachineLimits {
        v_max: [500.0, 500.0, 250.0],
        a_max: [5000.0, 5000.0, 2500.0],
        a_centripetal: f64::INFINITY,
        corner_angle_deg: 30.0,
    };
    let cases: Vec<(&str, Vec<DVec3>)> = vec![
        (
            "line 200",
            paths::line(DVec3::ZERO, DVec3::new(200.0, 0.0, 0.0), 0.5),
        ),
        (
            "diagonal 200",
            paths::line(DVec3::ZERO, DVec3::new(120.0, 160.0, 0.0), 0.5),
        ),
        ("circle R50", paths::circle(50.0, 0.5)),
        ("circle R10", paths::circle(10.0, 0.1)),
        ("pentagon R60 r10", paths::rounded_pentagon(60.0, 10.0, 0.5)),
        ("pentagon R60 r3", paths::rounded_pentagon(60.0, 3.0, 0.2)),
        ("spiral 5-60 p5", paths::spiral(5.0, 60.0, 5.0, 0.5)),
        (
            "zigzag-r 100x60 s10",
            paths::zigzag_rounded(100.0, 60.0, 10.0, 0.5),
        ),
        ("helix R10 p2 x3", paths::helix(10.0, 2.0, 3.0, 0.2)),
    ];

    let mut json_paths = Vec::new();
    let mut ours = Vec::new();
    for (name, pts) in &cases {
        let turn = max_turn_deg(pts);
        assert!(
            turn < limits.corner_angle_deg,
            "{name}: turning angle {turn}° is a corner"
        );
        let sched = schedule_polyline_uniform(pts, 1e6, &limits);
        ours.push((sched.total_time, pts.len(), sched.length));
        json_paths.push(serde_json::json!({
            "name": name,
            "points": pts.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(),
            "v_max": limits.v_max,
            "a_max": limits.a_max,
        }));
    }
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    std::fs::create_dir_all(&dir).expect("create output dir");
    let json_file = dir.join("toppra_paths.json");
    std::fs::write(
        &json_file,
        serde_json::to_vec(&serde_json::json!({ "paths": json_paths })).unwrap(),
    )
    .expect("write paths JSON");
    eprintln!("paths written to {}", json_file.display());

    let venv = std::env::var_os("THINPLAN_VENV")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(std::env::var_os("HOME").unwrap_or_default()).join(".cache/thinplan-venv")
        });
    let python = venv.join("bin/python");
    let script =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tools/peers/toppra/toppra_time.py");
    // TOPP-RA time, gridpoints, and our time on TOPP-RA's own curve (its spline sampled at
    // 32 points per segment): the same-curve comparison.
    let mut theirs: Vec<Option<(f64, u64, f64)>> = vec![None; cases.len()];
    let mut scheme = String::new();
    if python.exists() {
        let out = Command::new(&python)
            .arg(&script)
            .arg(&json_file)
            .args(["--resample", "32"])
            .args(&script_args)
            .output()
            .expect("run toppra_time.py");
        if out.status.success() {
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("TOPP-RA JSON");
            scheme = format!("toppra {} ({})", v["toppra_version"], v["scheme"]);
            for (i, r) in v["results"].as_array().unwrap().iter().enumerate() {
                let same: Option<Vec<DVec3>> = r["resampled"].as_array().and_then(|a| {
                    a.iter()
                        .map(|q| {
                            let c = |k: usize| q.get(k).and_then(|x| x.as_f64());
                            Some(DVec3::new(c(0)?, c(1)?, c(2).unwrap_or(0.0)))
                        })
                        .collect()
                });
                theirs[i] = r["time"].as_f64().zip(same).map(|(t, pts)| {
                    let ours_same = schedule_polyline_uniform(&pts, 1e6, &limits).total_time;
                    (t, r["gridpoints"].as_u64().unwrap_or(0), ours_same)
                });
            }
        } else {
            eprintln!(
                "toppra_time.py failed:\n{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    } else {
        eprintln!(
            "no venv at {} (run tools/peers/toppra/setup.sh): TOPP-RA column left empty",
            venv.display()
        );
    }

    if !scheme.is_empty() {
        println!("TOPP-RA: {scheme}");
    }
    println!(
        "| path | points | length (mm) | ours, own points (s) | ours, TOPP-RA's curve (s) | \
         TOPP-RA (s) | grid | ratio, same curve | ratio, own points |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (i, (name, _)) in cases.iter().enumerate() {
        let (t, n, len) = ours[i];
        match theirs[i] {
            Some((tt, grid, same)) => println!(
                "| {name} | {n} | {len:.1} | {t:.6} | {same:.6} | {tt:.6} | {grid} | {:.4} | {:.4} |",
                same / tt,
                t / tt
            ),
            None => println!("| {name} | {n} | {len:.1} | {t:.6} | – | – | – | – | – |"),
        }
    }
}
