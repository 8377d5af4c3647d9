use std::collections::BTreeMap;
use std::path::Path;

use glam::DVec3;
use thinplan_plan::*;

fn sample_plan() -> Plan {
    let setup = Setup {
        up: DVec3::Z,
        machine: "hsm_5axis".into(),
        tool_set: "endmills_12_20".into(),
        material: "al7075".into(),
        provenance: Provenance::new(ProvenanceSource::Default, "setup.default"),
    };
    let part = PartRef {
        source: "builtin:tall_rib".into(),
        format: PartFormat::Native,
        sha256: "00".repeat(32),
        declared_units: "mm".into(),
        summary: PartSummary {
            solids: 1,
            faces: 10,
            bbox: [120.0, 20.0, 82.0],
            volume: 12345.5,
        },
    };
    let mut plan = Plan::new(part, setup);
    plan.stiffness_features.push(StiffnessFeature {
        id: StiffnessFeatureId(0),
        kind: StiffnessKind::Wall,
        role: Some(WallRole::Rib),
        faces: vec![3, 4],
        axis: DVec3::Y,
        thickness: Some(1.0),
        height: 72.0,
        length: 120.0,
        diameter: None,
        shape: None,
        access: vec![DVec3::Y, -DVec3::Y],
        provenance: Provenance::new(ProvenanceSource::Recogniser, "recognise.wall")
            .with_value("thickness", 1.0)
            .with_value("height", 72.0),
    });
    plan.stages_done.push(Stage::Recognise);
    plan.notes = BTreeMap::from([("b".into(), "2".into()), ("a".into(), "1".into())]);
    plan
}

#[test]
fn save_then_load_gives_the_same_plan() {
    let dir = tempdir();
    let path = dir.join("p.plan.json");
    let plan = sample_plan();
    save(&plan, &path).unwrap();
    let back = load(&path).unwrap();
    assert_eq!(plan, back);
    // No temporary file is left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn same_plan_same_bytes() {
    let a = io::to_bytes(&sample_plan());
    let b = io::to_bytes(&sample_plan().clone());
    assert_eq!(a, b);
    // Ordered maps: "a" is written before "b" whatever the insertion order.
    let text = String::from_utf8(a).unwrap();
    let ia = text.find("\"a\"").unwrap();
    let ib = text.find("\"b\"").unwrap();
    assert!(ia < ib);
}

#[test]
fn save_replaces_existing_file_completely() {
    let dir = tempdir();
    let path = dir.join("p.plan.json");
    std::fs::write(&path, vec![b'x'; 100_000]).unwrap();
    save(&sample_plan(), &path).unwrap();
    assert_eq!(load(&path).unwrap(), sample_plan());
}

#[test]
fn corrupt_file_names_file_line_and_column() {
    let dir = tempdir();
    let path = dir.join("bad.plan.json");
    let mut text = String::from_utf8(io::to_bytes(&sample_plan())).unwrap();
    // Break the JSON on a known line.
    let line_of_break = text[..text.find("\"setup\"").unwrap()].lines().count();
    text = text.replacen("\"setup\": {", "\"setup\": {{", 1);
    std::fs::write(&path, &text).unwrap();
    let err = load(&path).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("bad.plan.json"), "{msg}");
    match err {
        PlanIoError::Corrupt { line, .. } => assert_eq!(line, line_of_break, "{msg}"),
        other => panic!("wrong error: {other}"),
    }
}

#[test]
fn unknown_field_is_an_error_not_silently_dropped() {
    let dir = tempdir();
    let path = dir.join("extra.plan.json");
    let text = String::from_utf8(io::to_bytes(&sample_plan()))
        .unwrap()
        .replacen("\"setup\": {", "\"setup\": {\"spindle\": 3,", 1);
    std::fs::write(&path, text).unwrap();
    let msg = load(&path).unwrap_err().to_string();
    assert!(msg.contains("spindle"), "{msg}");
}

#[test]
fn newer_schema_is_refused_with_a_clear_message() {
    let dir = tempdir();
    let path = dir.join("new.plan.json");
    let text = String::from_utf8(io::to_bytes(&sample_plan()))
        .unwrap()
        .replacen(
            &format!("\"schema_version\": {SCHEMA_VERSION}"),
            "\"schema_version\": 999",
            1,
        );
    std::fs::write(&path, text).unwrap();
    let msg = load(&path).unwrap_err().to_string();
    assert!(msg.contains("999") && msg.contains("newer"), "{msg}");
}

#[test]
fn missing_file_is_a_read_error_naming_it() {
    let msg = load(Path::new("/nonexistent/x.plan.json"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("/nonexistent/x.plan.json"), "{msg}");
}

/// Every released schema version keeps a frozen file that must keep loading.
#[test]
fn frozen_version_1_plan_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/plan_v1.json");
    let plan = load(&path).unwrap();
    assert_eq!(plan.schema_version, SCHEMA_VERSION);
    assert_eq!(plan.part.source, "builtin:tall_rib");
    assert_eq!(plan.stiffness_features.len(), 1);
    assert_eq!(plan.stiffness_features[0].thickness, Some(1.0));
    assert_eq!(plan.stiffness_features[0].role, Some(WallRole::Rib));
}

#[test]
fn invalidation_drops_only_downstream_results() {
    let mut plan = sample_plan();
    plan.invalidate_from(Stage::Sequence);
    assert_eq!(plan.stiffness_features.len(), 1);
    assert!(plan.stages_done.contains(&Stage::Recognise));
    plan.invalidate_from(Stage::Recognise);
    assert!(plan.stiffness_features.is_empty());
    assert_eq!(plan.stages_done, vec![Stage::Import, Stage::Setup]);
}

fn tempdir() -> std::path::PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "thinplan-plan-test-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes the frozen fixture of the current version; run by hand once per
/// released schema version: `cargo test -p thinplan-plan -- --ignored write_fixture`.
#[test]
#[ignore]
fn write_fixture() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("tests/fixtures/plan_v{SCHEMA_VERSION}.json"));
    save(&sample_plan(), &path).unwrap();
}

/// A v1 plan with a machining feature (hand-written, v1 had no
/// `hole_adjacency`) migrates to an empty adjacency list per hole.
#[test]
fn version_1_features_gain_hole_adjacency() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/plan_v1_features.json");
    let plan = load(&path).unwrap();
    let f = &plan.machining_features[0];
    assert_eq!(f.shape.region.holes.len(), 1);
    assert_eq!(
        f.hole_adjacency,
        vec![Vec::<thinplan_plan::Adjacency>::new()]
    );
    assert_eq!(f.side_adjacency.len(), 4);
}

/// A v2 plan (hand-written: v2 kept a feature's origin and access and an
/// operation's schedule only in the provenance) migrates to the typed
/// fields: what stages 6–8 read is the same as what they read before.
#[test]
fn version_2_provenance_becomes_typed_fields() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/plan_v2_provenance.json");
    let plan = load(&path).unwrap();
    assert_eq!(plan.schema_version, SCHEMA_VERSION);
    let f = &plan.machining_features;
    assert_eq!(f[0].origin.rule, "strategies.wall_steps");
    assert_eq!(f[0].origin.large, Some(true));
    assert!(!f[0].access_blocked);
    assert_eq!(f[1].origin.rule, "resolve.remaining");
    assert_eq!(f[1].origin.large, None);
    assert!(f[1].access_blocked);
    let s: Vec<Schedule> = plan.operations.iter().map(|o| o.schedule).collect();
    assert_eq!(
        s,
        vec![
            Schedule::WithFeature,
            Schedule::AfterFeature,
            Schedule::AfterFeature,
            Schedule::AtEnd {
                covered_within_mm: None
            },
            Schedule::AtEnd {
                covered_within_mm: Some(0.25)
            },
        ]
    );
}
