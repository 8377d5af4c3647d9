//! Against TOPP-RA (needs Python: `bash tools/peers/toppra/setup.sh` first), so ignored by
//! default:
//!
//!     cargo test -p thinplan-feeds --test toppra_peer -- --ignored
//!
//! Same per-axis limits, centripetal cap off, no corners, and the same curve: TOPP-RA's cubic
//! spline through our points, which our schedule times sampled at 32 points per segment (a
//! polyline and the spline through it are different paths; see the README). Target: within
//! 1 %, and not faster than TOPP-RA by more than the discretisation of both (0.3 %). The ratio
//! on our own points is printed too.

use glam::DVec3;
use std::path::PathBuf;
use std::process::Command;
use thinplan_feeds::{paths, schedule_polyline_uniform, MachineLimits};

#[test]
#[ignore = "needs the TOPP-RA venv (tools/peers/toppra/setup.sh)"]
fn within_one_percent_of_toppra() {
    let limits = MachineLimits {
        a_centripetal: f64::INFINITY,
        ..MachineLimits::typical_hsm()
    };
    let cases: Vec<(&str, Vec<DVec3>)> = vec![
        (
            "line",
            paths::line(DVec3::ZERO, DVec3::new(60.0, 80.0, 0.0), 0.5),
        ),
        ("circle", paths::circle(30.0, 0.5)),
        ("rounded pentagon", paths::rounded_pentagon(40.0, 8.0, 0.5)),
        ("spiral", paths::spiral(4.0, 30.0, 5.0, 0.5)),
        (
            "zigzag rounded",
            paths::zigzag_rounded(60.0, 30.0, 10.0, 0.5),
        ),
        ("helix", paths::helix(10.0, 2.0, 2.0, 0.3)),
    ];
    let json = serde_json::json!({ "paths": cases.iter().map(|(name, p)| serde_json::json!({
        "name": name,
        "points": p.iter().map(|q| [q.x, q.y, q.z]).collect::<Vec<_>>(),
        "v_max": limits.v_max,
        "a_max": limits.a_max,
    })).collect::<Vec<_>>() });
    let file =
        std::env::temp_dir().join(format!("thinplan_feeds_toppra_{}.json", std::process::id()));
    std::fs::write(&file, serde_json::to_vec(&json).unwrap()).unwrap();

    let venv = std::env::var_os("THINPLAN_VENV")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(std::env::var_os("HOME").unwrap()).join(".cache/thinplan-venv")
        });
    let script =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tools/peers/toppra/toppra_time.py");
    let out = Command::new(venv.join("bin/python"))
        .arg(script)
        .arg(&file)
        .args(["--grid-factor", "16", "--resample", "32"])
        .output()
        .expect("run toppra_time.py (did you run tools/peers/toppra/setup.sh?)");
    let _ = std::fs::remove_file(&file);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for (i, (name, p)) in cases.iter().enumerate() {
        let r = &v["results"][i];
        let theirs = r["time"]
            .as_f64()
            .unwrap_or_else(|| panic!("{name}: TOPP-RA failed"));
        let curve: Vec<DVec3> = r["resampled"]
            .as_array()
            .expect("resampled curve")
            .iter()
            .map(|q| {
                let c = |k: usize| q.get(k).and_then(|x| x.as_f64()).unwrap_or(0.0);
                DVec3::new(c(0), c(1), c(2))
            })
            .collect();
        let same = schedule_polyline_uniform(&curve, 1e6, &limits).total_time;
        let own = schedule_polyline_uniform(p, 1e6, &limits).total_time;
        let ratio = same / theirs;
        println!(
            "{name}: TOPP-RA {theirs:.6} s; ours on its curve {same:.6} s, ratio {ratio:.4}; \
             on our points {own:.6} s, ratio {:.4}",
            own / theirs
        );
        assert!((0.997..=1.01).contains(&ratio), "{name}: ratio {ratio}");
    }
}
