//! Tool reach, end to end: a level is cut only by a tool
//! whose holder clears the top of the stock; what no tool of the set reaches
//! is refused with the tool that would do, and the verdict says incomplete.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

mod common;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The repository's knowledge with one more tool set, `short`: a single
/// Ø12 end mill with 30 mm flutes whose holder face is 40 mm above its tip.
fn knowledge_with_short_tool(d: &Path) -> PathBuf {
    common::knowledge_with_tool_set(
        d,
        &repo().join("knowledge"),
        "short",
        r#"(
    id: "short",
    name: "One Ø12 end mill that reaches 38 mm",
    tools: [
        (
            id: "em12_short",
            kind: FlatEndMill,
            diameter: 12.0,
            corner_radius: 0.5,
            flutes: 3,
            flute_length: 30.0,
            stickout: 40.0,
            shank_diameter: 12.0,
            holder_diameter: 24.0,
            holder_length: 80.0,
            max_slot_depth_ratio: 0.5,
        ),
    ],
)
"#,
    )
}

/// `builtin:tall_rib` stands 72 mm over its web (top at 92). With a tool
/// that reaches 40 − `holder_clearance` (2) = 38 mm, nothing is cut below
/// 54; the features below are refused naming the reach they need; the
/// verdict is incomplete (exit 8), never unsafe, and the program is written.
#[test]
fn material_below_every_tools_reach_is_refused_naming_the_tool_that_would_do() {
    let d = std::env::temp_dir().join(format!("thinplan-reach-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let k = knowledge_with_short_tool(&d);
    let (plan, ngc) = (d.join("p.plan.json"), d.join("p.ngc"));
    let out = Command::new(env!("CARGO_BIN_EXE_thinplan"))
        .args(["plan", "builtin:tall_rib", "--tools", "short", "--json"])
        .arg("--knowledge")
        .arg(&k)
        .arg("--out")
        .arg(&plan)
        .arg("--gcode")
        .arg(&ngc)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(8),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["verdict"], "incomplete");
    assert!(ngc.is_file());
    let reasons: Vec<&str> = v["refused"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|r| r["reason"].as_str())
        .filter(|r| r.contains("no tool of the set-up's tool set reaches"))
        .collect();
    assert!(!reasons.is_empty(), "{}", v["refused"]);
    for r in &reasons {
        assert!(
            r.contains("em12_short") && r.contains("reaches 38.0 mm") && r.contains("needs D <="),
            "{r}"
        );
    }
    assert!(
        reasons.iter().any(|r| r.contains("with 72.0 mm reach")),
        "the web, 72 mm below the top: {reasons:#?}"
    );
    // No move of the program goes below what the tool reaches.
    let p: Value = serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
    let lowest = p["operations"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|o| o["moves"].as_array().unwrap())
        .map(|m| m["to"][2].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert!(lowest >= 54.0 - 1e-6, "a move at z {lowest}");
    assert!(p["operations"].as_array().unwrap().len() > 1);
}
