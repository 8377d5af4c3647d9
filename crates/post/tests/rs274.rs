//! LinuxCNC's own interpreter reads our program: no error, and the lengths
//! of its canonical moves equal ours within 0.1 %. Runs when the peer is
//! installed (`bash tools/peers/linuxcnc/setup.sh`); otherwise says so and
//! passes.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::*;
use thinplan_plan::OperationId;
use thinplan_post::post;

fn peer_root() -> Option<PathBuf> {
    let root = std::env::var_os("THINPLAN_LINUXCNC")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache/thinplan-linuxcnc"))
        })?;
    root.join("usr/bin/rs274").exists().then_some(root)
}

fn check(plan: &thinplan_plan::Plan, tag: &str) {
    let Some(root) = peer_root() else {
        thinplan_testdata::missing(
            "rs274 (bash tools/peers/linuxcnc/setup.sh puts it in ~/.cache/thinplan-linuxcnc)",
        );
        return;
    };
    let k = knowledge();
    let p = post(
        plan,
        k.post("linuxcnc").unwrap(),
        k.tool_set("endmills_12_20").unwrap(),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("thinplan-rs274-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (prog, tbl) = (dir.join("program.ngc"), dir.join("tools.tbl"));
    std::fs::write(&prog, &p.text).unwrap();
    std::fs::write(&tbl, &p.tool_table).unwrap();
    let script =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/peers/linuxcnc/rs274_check.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(&prog)
        .arg(&tbl)
        .arg("--skip")
        .arg(p.unmeasured_moves.to_string())
        .arg("--root")
        .arg(&root)
        .output()
        .expect("python3 runs");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    assert_eq!(report["ok"], true, "rs274: {}\n{}", report["error"], p.text);
    let theirs = |k: &str| report[k].as_f64().unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b.max(1e-9);
    eprintln!(
        "{tag}: feed ours {:.4} rs274 {:.4}; rapid ours {:.4} rs274 {:.4}; arcs {} / {}",
        p.feed_length_mm,
        theirs("feed_length_mm"),
        p.rapid_length_mm,
        theirs("rapid_length_mm"),
        p.arc_count,
        report["arc_count"]
    );
    assert!(
        rel(p.feed_length_mm, theirs("feed_length_mm")) < 1e-3,
        "{report}"
    );
    assert!(
        rel(p.rapid_length_mm, theirs("rapid_length_mm")) < 1e-3,
        "{report}"
    );
    assert_eq!(report["arc_count"].as_u64().unwrap() as usize, p.arc_count);
    assert_eq!(
        report["tool_changes"].as_u64().unwrap() as usize,
        p.tool_changes
    );
    assert_eq!(
        report["skipped_moves"].as_u64().unwrap() as usize,
        p.unmeasured_moves
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn rs274_reads_lines_arcs_helices_and_tool_changes_as_we_measure_them() {
    check(&rich_plan(), "rich");
}

#[test]
fn rs274_agrees_in_another_order_with_two_tool_changes() {
    let mut plan = rich_plan();
    plan.operation_order = vec![OperationId(3), OperationId(1), OperationId(2)];
    check(&plan, "reordered");
}

/// Arcs with awkward numbers: centres off the output grid, radii from
/// 0.3 mm to 800 mm, sweeps down to a hair (rounded to one point, so
/// written as a line), a helix with a fractional rise. The interpreter's
/// radius check (start vs end radius after rounding) must pass, and the
/// lengths must agree.
#[test]
fn rs274_reads_arcs_with_awkward_numbers() {
    use glam::DVec3;
    let mut plan = empty_plan();
    let mut moves = Vec::new();
    let mut p = DVec3::new(0.1234567, -0.7654321, -0.3333333);
    let z = DVec3::Z;
    let mut s = 0.123_f64;
    for i in 0..40 {
        // A deterministic pseudo-random walk of arcs.
        s = (s * 9301.0 + 49297.0) % 233280.0 / 233280.0 * 7.0 % 1.0;
        let r = [0.3, 1.7, 13.3, 97.1, 800.0][i % 5] * (0.9 + 0.2 * s);
        let sweep = [2.9, 0.4, 1e-4, 5.9, 0.05][(i / 5) % 5] * (0.7 + 0.3 * s);
        let a0 = s * 6.0;
        let c = p - r * DVec3::new(a0.cos(), a0.sin(), 0.0);
        let cw = i % 2 == 0;
        let a1 = if cw { a0 - sweep } else { a0 + sweep };
        let dz = if i % 3 == 0 { -0.1 * s } else { 0.0 };
        let to = c + r * DVec3::new(a1.cos(), a1.sin(), 0.0) + DVec3::new(0.0, 0.0, p.z - c.z + dz);
        moves.push(arc(
            to.into(),
            c.into(),
            if i % 4 == 1 { -z } else { z },
            cw ^ (i % 4 == 1),
            700.0,
        ));
        p = to;
    }
    plan.operations = vec![op(
        1,
        "em12",
        9000.0,
        [0.1234567, -0.7654321, -0.3333333],
        moves,
    )];
    check(&plan, "awkward");
}
