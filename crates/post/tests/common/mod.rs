//! Synthetic plans for the post tests (tool paths come from another stage).
#![allow(dead_code)]

use std::collections::BTreeMap;

use glam::DVec3;
use thinplan_knowledge::Knowledge;
use thinplan_plan::*;

pub fn knowledge() -> Knowledge {
    Knowledge::builtin().unwrap()
}

pub fn empty_plan() -> Plan {
    let part = PartRef {
        source: "builtin:test".into(),
        format: PartFormat::Native,
        sha256: "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef".into(),
        declared_units: "mm".into(),
        summary: PartSummary {
            solids: 1,
            faces: 6,
            bbox: [100.0, 50.0, 20.0],
            volume: 1e5,
        },
    };
    let setup = Setup {
        up: DVec3::Z,
        machine: "hsm_5axis".into(),
        tool_set: "endmills_12_20".into(),
        material: "al7075".into(),
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
    };
    let mut plan = Plan::new(part, setup);
    plan.notes = BTreeMap::from([("knowledge".to_string(), "builtin:knowledge".to_string())]);
    plan
}

pub fn line(x: f64, y: f64, z: f64, feed: f64) -> PathMove {
    PathMove {
        to: DVec3::new(x, y, z),
        arc: None,
        feed,
        region: if feed == 0.0 {
            Region3::Rapid
        } else {
            Region3::Rest
        },
    }
}

pub fn arc(to: [f64; 3], centre: [f64; 3], axis: DVec3, clockwise: bool, feed: f64) -> PathMove {
    PathMove {
        to: DVec3::from(to),
        arc: Some(ArcMove {
            centre: DVec3::from(centre),
            axis,
            clockwise,
        }),
        feed,
        region: Region3::Boundary,
    }
}

pub fn op(id: u32, tool: &str, rpm: f64, start: [f64; 3], moves: Vec<PathMove>) -> Operation {
    Operation {
        id: OperationId(id),
        feature: MachiningFeatureId(id),
        method: "test".into(),
        tool: tool.into(),
        tool_axis: DVec3::Z,
        spindle_rpm: rpm,
        start: DVec3::from(start),
        moves,
        schedule: Default::default(),
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
        link_z: None,
    }
}

/// Lines, arcs both ways (about +Z and −Z), helices (one a full turn), an
/// arc in the XZ plane, rapids, and tools em12 → em20 → em12.
pub fn rich_plan() -> Plan {
    let mut plan = empty_plan();
    let z = DVec3::Z;
    plan.operations = vec![
        op(
            1,
            "em12",
            12000.0,
            [5.0, 5.0, 3.0],
            vec![
                // Helical entry: two half turns of radius 4 about (9, 5).
                arc([13.0, 5.0, 1.0], [9.0, 5.0, 3.0], z, false, 800.0),
                arc([5.0, 5.0, -1.0], [9.0, 5.0, 1.0], z, false, 800.0),
                line(5.0, 40.0, -1.0, 1500.0),
                // Quarter arcs clockwise and counter-clockwise.
                arc([15.0, 50.0, -1.0], [15.0, 40.0, -1.0], z, true, 1500.0),
                arc([25.0, 60.0, -1.0], [15.0, 60.0, -1.0], -z, true, 1500.0),
                line(60.0, 60.0, -1.0, 1500.0),
                // A full circle, and a full-turn helix down to −3.
                arc([60.0, 60.0, -1.0], [60.0, 52.0, -1.0], z, true, 1200.0),
                arc([60.0, 60.0, -3.0], [60.0, 52.0, -1.0], z, false, 1200.0),
                line(60.0, 60.0, 8.0, 0.0),
                line(80.0, 10.0, 8.0, 0.0),
                line(80.0, 10.0, -2.0, 400.0),
                line(95.5, 10.25, -2.0, 1500.0),
            ],
        ),
        op(
            2,
            "em20",
            8000.0,
            [0.0, -15.0, 2.0],
            vec![
                line(0.0, -15.0, -4.0, 300.0),
                line(100.0, -15.0, -4.0, 2000.0),
                // A semicircle in the XZ plane (linearised).
                arc(
                    [100.0, -15.0, -4.0 + 0.0],
                    [100.0, -15.0, 6.0],
                    DVec3::Y,
                    false,
                    1000.0,
                ),
                line(100.0, -15.0, 10.0, 0.0),
            ],
        ),
        op(
            3,
            "em12",
            15000.0,
            [30.0, 30.0, 2.0],
            vec![
                line(30.0, 30.0, -0.5, 300.0),
                arc([30.0, 30.0, -0.5], [36.0, 30.0, -0.5], z, false, 900.0),
                arc([42.0, 30.0, -0.5], [36.0, 30.0, -0.5], z, true, 900.0),
            ],
        ),
    ];
    // The XZ semicircle: from (100,-15,-4) about (100,-15,6) … make it go
    // to the top of the circle instead of back to its start.
    plan.operations[1].moves[2].to = DVec3::new(100.0, -15.0, 16.0);
    plan.operations[1].moves[3].to = DVec3::new(100.0, -15.0, 20.0);
    plan.operation_order = vec![OperationId(1), OperationId(2), OperationId(3)];
    plan
}
