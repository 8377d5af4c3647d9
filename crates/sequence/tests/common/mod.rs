//! Hand-built stiffness features for the sequencing tests.
#![allow(dead_code, clippy::too_many_arguments)]

use std::path::Path;

use glam::DVec3;
use thinplan_knowledge::{parse_ron, SequencingKnowledge};
use thinplan_plan::*;

pub const UP: DVec3 = DVec3::Z;

pub fn id(n: u32) -> StiffnessFeatureId {
    StiffnessFeatureId(n)
}

fn rect(w: f64, h: f64) -> Region {
    let v = |x, y| ProfileVertex { x, y, bulge: 0.0 };
    Region {
        outer: ProfileLoop {
            vertices: vec![v(0.0, 0.0), v(w, 0.0), v(w, h), v(0.0, h)],
        },
        holes: vec![],
    }
}

fn prov(what: &str) -> Provenance {
    Provenance::new(ProvenanceSource::User, format!("test.{what}"))
}

/// A flat wall: mid-plane through `origin`, normal `normal`, its side
/// outline the rectangle `[0, w] × [0, h]` in the frame (x = `xdir`,
/// y = normal × xdir), thickness `t`.
pub fn wall(
    n: u32,
    role: WallRole,
    normal: DVec3,
    origin: DVec3,
    xdir: DVec3,
    w: f64,
    h: f64,
    t: f64,
) -> StiffnessFeature {
    StiffnessFeature {
        id: id(n),
        kind: StiffnessKind::Wall,
        role: Some(role),
        faces: vec![],
        axis: normal,
        thickness: Some(t),
        height: h,
        length: w,
        diameter: None,
        shape: Some(Prism {
            frame: PrismFrame {
                origin,
                x: xdir,
                z: normal,
            },
            region: rect(w, h),
            z_min: -t / 2.0,
            z_max: t / 2.0,
        }),
        access: vec![],
        provenance: prov("wall"),
    }
}

/// A round hole of diameter `d` through a wall of thickness `t`, centred
/// at `centre`, along `axis`; its profile is two half-circle arcs.
pub fn hole(n: u32, centre: DVec3, axis: DVec3, xdir: DVec3, d: f64, t: f64) -> StiffnessFeature {
    let r = d / 2.0;
    StiffnessFeature {
        id: id(n),
        kind: StiffnessKind::Hole,
        role: None,
        faces: vec![],
        axis,
        thickness: None,
        height: t,
        length: d,
        diameter: Some(d),
        shape: Some(Prism {
            frame: PrismFrame {
                origin: centre,
                x: xdir,
                z: axis,
            },
            region: Region {
                outer: ProfileLoop {
                    vertices: vec![
                        ProfileVertex {
                            x: r,
                            y: 0.0,
                            bulge: 1.0,
                        },
                        ProfileVertex {
                            x: -r,
                            y: 0.0,
                            bulge: 1.0,
                        },
                    ],
                },
                holes: vec![],
            },
            z_min: -t / 2.0,
            z_max: t / 2.0,
        }),
        access: vec![],
        provenance: prov("hole"),
    }
}

/// A rectangular depression of kind `kind`, `[0, w] × [0, h]` in its frame,
/// swept over `[0, depth]` along `axis`.
pub fn depression(
    n: u32,
    kind: StiffnessKind,
    origin: DVec3,
    axis: DVec3,
    xdir: DVec3,
    w: f64,
    h: f64,
    depth: f64,
) -> StiffnessFeature {
    StiffnessFeature {
        id: id(n),
        kind,
        role: None,
        faces: vec![],
        axis,
        thickness: None,
        height: depth,
        length: w,
        diameter: None,
        shape: Some(Prism {
            frame: PrismFrame {
                origin,
                x: xdir,
                z: axis,
            },
            region: rect(w, h),
            z_min: 0.0,
            z_max: depth,
        }),
        access: vec![],
        provenance: prov("depression"),
    }
}

pub fn base_leaf(base: u32, leaf: u32) -> Connection {
    Connection {
        base: id(base),
        leaf: id(leaf),
        kind: ConnectionKind::BaseLeaf,
        provenance: prov("connection"),
    }
}

/// The thesis-like part, up = +z:
///
/// - SF1 web: a vertical wall, normal x, 200 long (y), 100 high (z 0..100), 2 thick;
/// - SF2 flange: horizontal (normal z) on the web's top, z 100..102, x −20..20;
/// - SF3 vertical rib: normal y, standing on the web's +x side, full height;
/// - SF4 horizontal rib: normal z, on the web's −x side at mid-height (z 49..51);
/// - SF5 hole Ø10 through the vertical rib, centre z = 70 (z 65..75);
/// - SF6 cut-out through the flange.
pub fn thesis_part() -> (Vec<StiffnessFeature>, Vec<Connection>) {
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let features = vec![
        wall(1, WallRole::Web, x, DVec3::ZERO, y, 200.0, 100.0, 2.0),
        wall(
            2,
            WallRole::Flange,
            z,
            DVec3::new(20.0, 0.0, 101.0),
            y,
            200.0,
            40.0,
            2.0,
        ),
        wall(
            3,
            WallRole::Rib,
            y,
            DVec3::new(41.0, 100.0, 0.0),
            -x,
            40.0,
            100.0,
            2.0,
        ),
        wall(
            4,
            WallRole::Rib,
            z,
            DVec3::new(-1.0, 0.0, 50.0),
            y,
            200.0,
            30.0,
            2.0,
        ),
        hole(5, DVec3::new(20.0, 100.0, 70.0), y, x, 10.0, 2.0),
        depression(
            6,
            StiffnessKind::Cutout,
            DVec3::new(-5.0, 80.0, 100.0),
            z,
            x,
            10.0,
            20.0,
            2.0,
        ),
    ];
    let connections = vec![
        base_leaf(1, 2),
        base_leaf(1, 3),
        base_leaf(1, 4),
        base_leaf(3, 5),
        base_leaf(2, 6),
    ];
    (features, connections)
}

pub fn repo_sequencing_text() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge/sequencing.ron"),
    )
    .unwrap()
}

pub fn rules(text: &str) -> SequencingKnowledge {
    let k: SequencingKnowledge = parse_ron(text, Path::new("sequencing.ron")).unwrap();
    assert!(k.problems().is_empty(), "{:?}", k.problems());
    k
}

pub fn repo_rules() -> SequencingKnowledge {
    rules(&repo_sequencing_text())
}

/// Whether `s` holds a constraint `first kind second` (either way round for
/// simultaneous), made by `rule` (without the `sequencing.` prefix).
pub fn has(
    s: &thinplan_sequence::Sequencing,
    first: u32,
    kind: ConstraintKind,
    second: u32,
    rule: &str,
) -> bool {
    s.constraints.iter().any(|c| {
        c.kind == kind
            && c.provenance.rule == format!("sequencing.{rule}")
            && ((c.first, c.second) == (id(first), id(second))
                || (kind == ConstraintKind::Simultaneous
                    && (c.first, c.second) == (id(second), id(first))))
    })
}

pub fn position(order: &[StiffnessFeatureId], n: u32) -> usize {
    order.iter().position(|x| *x == id(n)).unwrap()
}
