//! End-to-end tests of `thinplan pocket` and `thinplan bench pockets`.
//!
//! The path is checked independently of the pocketing crate: the profile's arcs are sampled
//! here from the bulges, and every path point must lie inside the pocket and at least the tool
//! radius from its wall (the pocket offset by the tool radius).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn thinplan() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thinplan"))
}

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../pocketing/examples/pentagon.pocket.json")
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("thinplan-pocket-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Sample a closed loop of `[x, y, bulge]` vertices (arcs from the bulges) at ≤ `step` mm.
fn sample_profile(vs: &[Value], step: f64) -> Vec<[f64; 2]> {
    let v: Vec<[f64; 3]> = vs
        .iter()
        .map(|v| {
            let a = v.as_array().unwrap();
            [
                a[0].as_f64().unwrap(),
                a[1].as_f64().unwrap(),
                a.get(2).and_then(|b| b.as_f64()).unwrap_or(0.0),
            ]
        })
        .collect();
    let mut out = Vec::new();
    for i in 0..v.len() {
        let [x0, y0, b] = v[i];
        let [x1, y1, _] = v[(i + 1) % v.len()];
        let chord = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        if b.abs() < 1e-12 {
            let k = (chord / step).ceil().max(1.0) as usize;
            for j in 0..k {
                let t = j as f64 / k as f64;
                out.push([x0 + t * (x1 - x0), y0 + t * (y1 - y0)]);
            }
        } else {
            // arc: sweep = 4 atan(b); centre on the chord's bisector
            let sweep = 4.0 * b.atan();
            let r = chord / (2.0 * (sweep / 2.0).sin().abs());
            let (mx, my) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
            let (dx, dy) = ((x1 - x0) / chord, (y1 - y0) / chord);
            let h = (r * r - chord * chord / 4.0).max(0.0).sqrt();
            // for a counter-clockwise arc (b > 0) with sweep < π the centre is to the left
            let side = if (b > 0.0) == (sweep.abs() < std::f64::consts::PI) {
                1.0
            } else {
                -1.0
            };
            let (cx, cy) = (mx - side * dy * h, my + side * dx * h);
            let a0 = (y0 - cy).atan2(x0 - cx);
            let k = ((r * sweep.abs()) / step).ceil().max(8.0) as usize;
            for j in 0..k {
                let a = a0 + sweep * j as f64 / k as f64;
                out.push([cx + r * a.cos(), cy + r * a.sin()]);
            }
        }
    }
    out
}

fn inside(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let mut c = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
        {
            c = !c;
        }
        j = i;
    }
    c
}

fn dist_to_loop(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
            let l2 = abx * abx + aby * aby;
            let t = if l2 > 0.0 {
                (((p[0] - a[0]) * abx + (p[1] - a[1]) * aby) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            ((p[0] - a[0] - t * abx).powi(2) + (p[1] - a[1] - t * aby).powi(2)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn pocket_example_writes_svg_and_a_path_inside_the_tool_offset_pocket() {
    let d = tmp("example");
    let svg = d.join("pentagon.svg");
    let out = thinplan()
        .arg("pocket")
        .arg(example())
        .arg("--svg")
        .arg(&svg)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let text = std::fs::read_to_string(&svg).expect("SVG written");
    assert!(text.contains("<svg") && text.trim_end().ends_with("</svg>"));

    let profile: Value =
        serde_json::from_str(&std::fs::read_to_string(example()).unwrap()).unwrap();
    let tool = profile["tool_diameter"].as_f64().unwrap();
    let stepover = profile["stepover"].as_f64().unwrap();
    let r = tool / 2.0;
    let wall = sample_profile(profile["outer"].as_array().unwrap(), 0.05);

    assert_eq!(v["method"], "curvilinear", "{}", v["fallback_reason"]);
    let max_gap = v["max_gap_mm"].as_f64().unwrap();
    assert!(max_gap > 0.0 && max_gap <= stepover + 1e-9, "gap {max_gap}");
    let pts = v["points"].as_array().unwrap();
    assert!(pts.len() > 100);
    let mut length = 0.0;
    let mut prev: Option<[f64; 2]> = None;
    for (i, p) in pts.iter().enumerate() {
        let a = p.as_array().unwrap();
        let q = [a[0].as_f64().unwrap(), a[1].as_f64().unwrap()];
        let feed = a[2].as_f64().unwrap();
        assert!(
            (0.0..=500.0 + 1e-6).contains(&feed),
            "point {i}: feed {feed}"
        );
        assert!(inside(q, &wall), "point {i} {q:?} outside the pocket");
        let dw = dist_to_loop(q, &wall);
        // the sampled wall lies inside the true arcs: chord sagitta at 0.05 mm is negligible
        assert!(
            dw >= r - 1e-3,
            "point {i} {q:?}: {dw} mm from the wall < R = {r}"
        );
        if let Some(pp) = prev {
            let step = ((q[0] - pp[0]).powi(2) + (q[1] - pp[1]).powi(2)).sqrt();
            assert!(step <= stepover + 1e-9, "point {i}: jump of {step} mm");
            length += step;
        }
        prev = Some(q);
    }
    // ends and starts at rest; the reported length is the polyline's
    assert_eq!(pts[0][2].as_f64().unwrap(), 0.0);
    assert_eq!(pts.last().unwrap()[2].as_f64().unwrap(), 0.0);
    let reported = v["length_mm"].as_f64().unwrap();
    assert!(
        (length - reported).abs() < 1e-6 * reported,
        "{length} vs {reported}"
    );
    assert!(v["time_s"].as_f64().unwrap() > reported / 500.0);
    let _ = std::fs::remove_dir_all(&d);
}

fn run_pocket(file: &Path) -> Output {
    thinplan().arg("pocket").arg(file).output().unwrap()
}

fn assert_fails_naming(out: &Output, file: &Path, reason: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "succeeded on {}", file.display());
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains(&file.display().to_string()),
        "file not named: {stderr}"
    );
    assert!(
        stderr.contains(reason),
        "reason `{reason}` missing: {stderr}"
    );
}

#[test]
fn bad_profiles_fail_naming_the_file_and_the_reason() {
    let d = tmp("bad");
    let missing = d.join("missing.pocket.json");
    assert_fails_naming(&run_pocket(&missing), &missing, "cannot read");

    let bad_json = d.join("bad.pocket.json");
    std::fs::write(&bad_json, "{\"tool_diameter\": 10, \"outer\": [[0,0],").unwrap();
    assert_fails_naming(&run_pocket(&bad_json), &bad_json, "bad JSON");

    let bowtie = d.join("bowtie.pocket.json");
    std::fs::write(
        &bowtie,
        r#"{"tool_diameter": 4, "outer": [[0,0],[100,100],[100,0],[0,100]]}"#,
    )
    .unwrap();
    assert_fails_naming(&run_pocket(&bowtie), &bowtie, "intersects itself");

    let big_tool = d.join("bigtool.pocket.json");
    std::fs::write(
        &big_tool,
        r#"{"tool_diameter": 30, "outer": [[0,0],[20,0],[20,20],[0,20]]}"#,
    )
    .unwrap();
    assert_fails_naming(&run_pocket(&big_tool), &big_tool, "does not fit");

    // --json reports the error as JSON on stdout
    let out = thinplan()
        .arg("pocket")
        .arg(&big_tool)
        .arg("--json")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["error"]
        .as_str()
        .unwrap()
        .contains(&big_tool.display().to_string()));

    // RON is accepted too
    let ron = d.join("square.pocket.ron");
    std::fs::write(
        &ron,
        "(tool_diameter: 10.0, outer: [(0.0, 0.0), (80.0, 0.0), (80.0, 60.0), (0.0, 60.0)])",
    )
    .unwrap();
    let out = run_pocket(&ron);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Slow (minutes): `cargo test -p thinplan-cli --test pocket_cmd -- --ignored`.
#[test]
#[ignore]
fn bench_pockets_json_rows_follow_the_contract() {
    let out = thinplan()
        .args(["bench", "pockets", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v.as_array().unwrap();
    assert!(rows.len() >= 10);
    for r in rows {
        assert!(r["pocket"].is_string());
        for k in ["l_over_d", "stepover_mm", "tool_mm"] {
            assert!(r[k].as_f64().unwrap() > 0.0, "{k}: {r}");
        }
        for k in ["offset", "curvilinear"] {
            assert!(r[k]["length_mm"].as_f64().unwrap() > 0.0);
            assert!(r[k]["time_s"].as_f64().unwrap() > 0.0);
        }
        assert!(r["curvilinear"]["method"].is_string());
        assert!(r["adaptive"].is_null() || r["adaptive"]["time_s"].as_f64().unwrap() > 0.0);
        assert!(r["toppra_ratio"].is_null() || r["toppra_ratio"].as_f64().unwrap() > 0.9);
    }
}
