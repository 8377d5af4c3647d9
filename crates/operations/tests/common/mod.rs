//! Synthetic plans and independent checks (geometry computed here, not by
//! the crate under test).
#![allow(dead_code)]

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_plan::*;

pub fn plan_with(features: Vec<MachiningFeature>) -> Plan {
    let setup = Setup {
        up: DVec3::Z,
        machine: "hsm_5axis".into(),
        tool_set: "endmills_12_20".into(),
        material: "al7075".into(),
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
    };
    let part = PartRef {
        source: "synthetic".into(),
        format: PartFormat::Native,
        sha256: String::new(),
        declared_units: "mm".into(),
        summary: PartSummary {
            solids: 1,
            faces: 0,
            bbox: [0.0; 3],
            volume: 0.0,
        },
    };
    let mut plan = Plan::new(part, setup);
    plan.machining_features = features;
    for s in [
        Stage::Recognise,
        Stage::Connect,
        Stage::Sequence,
        Stage::Determine,
        Stage::Resolve,
    ] {
        plan.stages_done.push(s);
    }
    plan
}

/// Records the blank's plan-view box as stage 6 does.
pub fn with_blank(plan: &mut Plan, b: [f64; 4]) {
    for (k, x) in [
        ("resolve.blank_min_x", b[0]),
        ("resolve.blank_min_y", b[1]),
        ("resolve.blank_max_x", b[2]),
        ("resolve.blank_max_y", b[3]),
    ] {
        plan.notes.insert(k.into(), x.to_string());
    }
}

pub fn v(x: f64, y: f64) -> ProfileVertex {
    ProfileVertex { x, y, bulge: 0.0 }
}

pub fn feature(
    id: u32,
    outer: Vec<ProfileVertex>,
    holes: Vec<Vec<ProfileVertex>>,
    side: Vec<Adjacency>,
    bottom: Adjacency,
    z: (f64, f64),
) -> MachiningFeature {
    let hole_adjacency = holes
        .iter()
        .map(|h| vec![Adjacency::Product; h.len()])
        .collect();
    MachiningFeature {
        id: MachiningFeatureId(id),
        owner: StiffnessFeatureId(0),
        shape: Prism {
            frame: PrismFrame {
                origin: DVec3::ZERO,
                x: DVec3::X,
                z: DVec3::Z,
            },
            region: Region {
                outer: ProfileLoop { vertices: outer },
                holes: holes
                    .into_iter()
                    .map(|vertices| ProfileLoop { vertices })
                    .collect(),
            },
            z_min: z.0,
            z_max: z.1,
        },
        side_adjacency: side,
        hole_adjacency,
        bottom_adjacency: bottom,
        slopes: None,
        origin: Default::default(),
        access_blocked: false,
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
    }
}

use Adjacency::{Feature, Open, Product};

/// An open step beside a wall: the wall (product) along y = 30.
pub fn step(id: u32) -> MachiningFeature {
    feature(
        id,
        vec![v(0.0, 0.0), v(100.0, 0.0), v(100.0, 30.0), v(0.0, 30.0)],
        vec![],
        vec![Open, Open, Product, Open],
        Feature,
        (0.0, 20.0),
    )
}

/// A closed 80 × 50 pocket with corner radius 8 and a product floor.
pub fn pocket(id: u32) -> MachiningFeature {
    let rc = 8.0;
    let b = (std::f64::consts::PI / 8.0).tan(); // quarter circle
    let (w, h) = (80.0, 50.0);
    let outer = vec![
        ProfileVertex {
            x: rc,
            y: 0.0,
            bulge: 0.0,
        },
        ProfileVertex {
            x: w - rc,
            y: 0.0,
            bulge: b,
        },
        ProfileVertex {
            x: w,
            y: rc,
            bulge: 0.0,
        },
        ProfileVertex {
            x: w,
            y: h - rc,
            bulge: b,
        },
        ProfileVertex {
            x: w - rc,
            y: h,
            bulge: 0.0,
        },
        ProfileVertex {
            x: rc,
            y: h,
            bulge: b,
        },
        ProfileVertex {
            x: 0.0,
            y: h - rc,
            bulge: 0.0,
        },
        ProfileVertex {
            x: 0.0,
            y: rc,
            bulge: b,
        },
    ];
    feature(id, outer, vec![], vec![Product; 8], Product, (0.0, 12.0))
}

/// An L-shaped feature, product on its two inner edges, with a square island.
pub fn l_with_island(id: u32) -> MachiningFeature {
    feature(
        id,
        vec![
            v(0.0, 0.0),
            v(120.0, 0.0),
            v(120.0, 40.0),
            v(50.0, 40.0),
            v(50.0, 90.0),
            v(0.0, 90.0),
        ],
        vec![vec![
            v(20.0, 15.0),
            v(20.0, 25.0),
            v(30.0, 25.0),
            v(30.0, 15.0),
        ]],
        vec![Open, Open, Product, Product, Open, Open],
        Feature,
        (0.0, 15.0),
    )
}

/// A rectangle with a product edge, a `Feature` edge and open edges.
pub fn with_feature_edge(id: u32) -> MachiningFeature {
    feature(
        id,
        vec![v(0.0, 0.0), v(60.0, 0.0), v(60.0, 40.0), v(0.0, 40.0)],
        vec![],
        vec![Product, Feature, Open, Open],
        Open,
        (0.0, 10.0),
    )
}

/// All open: no product anywhere (for mirrored layers).
pub fn open_block(id: u32) -> MachiningFeature {
    feature(
        id,
        vec![v(0.0, 0.0), v(50.0, 0.0), v(50.0, 20.0), v(0.0, 20.0)],
        vec![],
        vec![Open; 4],
        Open,
        (0.0, 12.0),
    )
}

/// Edges of a feature: (a, b, bulge, adjacency), outer then holes.
pub fn edges(f: &MachiningFeature) -> Vec<(DVec2, DVec2, f64, Adjacency)> {
    let mut out = Vec::new();
    let mut push = |l: &ProfileLoop, adj: &dyn Fn(usize) -> Adjacency| {
        let n = l.vertices.len();
        for i in 0..n {
            let a = &l.vertices[i];
            let b = &l.vertices[(i + 1) % n];
            out.push((DVec2::new(a.x, a.y), DVec2::new(b.x, b.y), a.bulge, adj(i)));
        }
    };
    push(&f.shape.region.outer, &|i| f.side_adjacency[i]);
    for (h, l) in f.shape.region.holes.iter().enumerate() {
        push(l, &|i| {
            f.hole_adjacency
                .get(h)
                .and_then(|a| a.get(i))
                .copied()
                .unwrap_or(Product)
        });
    }
    out
}

pub fn seg_dist(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Arc centre of a bulge edge.
pub fn bulge_centre(a: DVec2, b: DVec2, bulge: f64) -> (DVec2, f64) {
    let d = a.distance(b);
    let theta = 4.0 * bulge.atan();
    let r = d / (2.0 * (theta / 2.0).sin().abs());
    let m = (a + b) * 0.5;
    let left = (b - a).perp().normalize();
    let h = (r * r - d * d / 4.0).max(0.0).sqrt();
    // Counter-clockwise arcs of less than half a turn: centre on the left.
    let side = if (bulge > 0.0) == (theta.abs() < std::f64::consts::PI) {
        1.0
    } else {
        -1.0
    };
    (m + left * h * side, r)
}

/// Closest point on a profile edge (arcs sampled finely).
pub fn closest_on_edge(p: DVec2, a: DVec2, b: DVec2, bulge: f64) -> DVec2 {
    if bulge.abs() < 1e-12 {
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        return a + ab * t;
    }
    let (c, r) = bulge_centre(a, b, bulge);
    let sweep = 4.0 * bulge.atan();
    let a0 = (a - c).to_angle();
    // The angle of p from a, in the arc's sense: on the arc, or an end.
    let t = (((p - c).to_angle() - a0) * sweep.signum()).rem_euclid(std::f64::consts::TAU);
    if t <= sweep.abs() && (p - c).length() > 1e-12 {
        c + (p - c).normalize() * r
    } else if p.distance(a) <= p.distance(b) {
        a
    } else {
        b
    }
}

/// Points along the path of an operation with the move each belongs to:
/// (point, unit horizontal direction, region).
pub fn walk(op: &Operation, step: f64) -> Vec<(DVec3, DVec2, Region3)> {
    let mut out = Vec::new();
    let mut from = op.start;
    for m in &op.moves {
        let pts = move_points(from, m, step);
        let mut prev = from;
        for p in pts {
            let d = (p - prev).truncate();
            let dir = if d.length() > 1e-12 {
                d.normalize()
            } else {
                DVec2::ZERO
            };
            out.push((p, dir, m.region));
            prev = p;
        }
        from = m.to;
    }
    out
}

pub fn move_points(from: DVec3, m: &PathMove, step: f64) -> Vec<DVec3> {
    match &m.arc {
        None => {
            let k = (from.distance(m.to) / step).ceil().max(1.0) as usize;
            (1..=k)
                .map(|j| from.lerp(m.to, j as f64 / k as f64))
                .collect()
        }
        Some(a) => {
            let c = a.centre.truncate();
            let (p, q) = (from.truncate(), m.to.truncate());
            let r = (p - c).length();
            let mut sweep = (q - c).to_angle() - (p - c).to_angle();
            if a.clockwise {
                while sweep >= -1e-12 {
                    sweep -= std::f64::consts::TAU;
                }
            } else {
                while sweep <= 1e-12 {
                    sweep += std::f64::consts::TAU;
                }
            }
            let k = (r * sweep.abs() / step).ceil().max(4.0) as usize;
            (1..=k)
                .map(|j| {
                    let t = j as f64 / k as f64;
                    let xy = c + r * DVec2::from_angle((p - c).to_angle() + sweep * t);
                    xy.extend(from.z + (m.to.z - from.z) * t)
                })
                .collect()
        }
    }
}

pub fn is_cutting(r: Region3) -> bool {
    matches!(r, Region3::Boundary | Region3::FullCut | Region3::Rest)
}

/// Even-odd containment in the feature's region (arcs sampled).
pub fn region_polys(f: &MachiningFeature) -> Vec<Vec<DVec2>> {
    let mut loops = vec![&f.shape.region.outer];
    loops.extend(f.shape.region.holes.iter());
    loops
        .into_iter()
        .map(|l| {
            let n = l.vertices.len();
            let mut pts = Vec::new();
            for i in 0..n {
                let a = &l.vertices[i];
                let b = &l.vertices[(i + 1) % n];
                let (pa, pb) = (DVec2::new(a.x, a.y), DVec2::new(b.x, b.y));
                if a.bulge.abs() < 1e-12 {
                    pts.push(pa);
                } else {
                    let (c, r) = bulge_centre(pa, pb, a.bulge);
                    let sweep = 4.0 * a.bulge.atan();
                    for k in 0..64 {
                        pts.push(
                            c + r * DVec2::from_angle(
                                (pa - c).to_angle() + sweep * k as f64 / 64.0,
                            ),
                        );
                    }
                }
            }
            pts
        })
        .collect()
}

pub fn inside(p: DVec2, polys: &[Vec<DVec2>]) -> bool {
    let mut c = false;
    for pts in polys {
        let n = pts.len();
        let mut j = n - 1;
        for i in 0..n {
            let (a, b) = (pts[i], pts[j]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
                c = !c;
            }
            j = i;
        }
    }
    c
}

/// Tool radius of an operation, from the tool set.
pub fn radius(k: &thinplan_knowledge::Knowledge, op: &Operation) -> f64 {
    k.tool_set("endmills_12_20")
        .unwrap()
        .tools
        .iter()
        .find(|t| t.id == op.tool)
        .unwrap()
        .diameter
        / 2.0
}

/// Buckets of cutting segments per z-level (flat moves only), for coverage.
pub struct LevelIndex {
    pub cell: f64,
    pub segs: BTreeMap<(i64, i64), Vec<(DVec2, DVec2)>>,
}

impl LevelIndex {
    pub fn new(segs: &[(DVec2, DVec2)], cell: f64) -> Self {
        let mut m: BTreeMap<(i64, i64), Vec<(DVec2, DVec2)>> = BTreeMap::new();
        for &(a, b) in segs {
            let lo = a.min(b);
            let hi = a.max(b);
            for i in (lo.x / cell).floor() as i64..=(hi.x / cell).floor() as i64 {
                for j in (lo.y / cell).floor() as i64..=(hi.y / cell).floor() as i64 {
                    m.entry((i, j)).or_default().push((a, b));
                }
            }
        }
        LevelIndex { cell, segs: m }
    }

    pub fn nearest(&self, p: DVec2) -> f64 {
        let (ci, cj) = (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        );
        let mut best = f64::INFINITY;
        for i in ci - 1..=ci + 1 {
            for j in cj - 1..=cj + 1 {
                if let Some(v) = self.segs.get(&(i, j)) {
                    for &(a, b) in v {
                        best = best.min(seg_dist(p, a, b));
                    }
                }
            }
        }
        best
    }
}
