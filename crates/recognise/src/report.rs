//! The `recognize --json` contract and the SVG picture.
//!
//! JSON: `{"features": [...], "connections": [...]}`.
//! - A feature: `id` — the string `"SF<n>"` (the plan's
//!   `StiffnessFeatureId` display form; stable: ids are assigned in a
//!   deterministic order), `kind` (`wall`, `hole`, `cutout`, `slot`, `notch`,
//!   `pocket`, `step`, `chamfer`, `fillet`), `role` (`web`, `rib`, `flange`
//!   for walls, else `null`), `thickness` (mm, walls; else `null`), `height`,
//!   `length` (mm), `axis` (`[x, y, z]`, unit: wall normal or depression
//!   axis, part coordinates), `faces` (ascending face indices), `face_names`
//!   (the faces' names in the same order as `faces`; a face without a name
//!   gives `""`, so both arrays always have the same length), `diameter`
//!   (round holes, else `null`), `access` (reachable tool directions).
//! - A connection: `base`, `leaf` (feature ids as above), `kind`
//!   (`base_leaf` or `crossing`; for a crossing the order is not meaningful).
//!
//! Numbers are rounded to 1e-6 mm so the output is stable across platforms.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use glam::{DVec2, DVec3};
use serde_json::{json, Value};
use thinplan_brep::{Brep, TessTolerance};
use thinplan_plan::{ConnectionKind, StiffnessKind, WallRole};

use crate::Recognition;

fn r6(x: f64) -> f64 {
    let v = (x * 1e6).round() / 1e6;
    if v == 0.0 {
        0.0
    } else {
        v
    }
}

fn vec3(v: DVec3) -> Value {
    json!([r6(v.x), r6(v.y), r6(v.z)])
}

/// The JSON name of a kind.
pub fn kind_name(k: StiffnessKind) -> &'static str {
    match k {
        StiffnessKind::Wall => "wall",
        StiffnessKind::Hole => "hole",
        StiffnessKind::Cutout => "cutout",
        StiffnessKind::Slot => "slot",
        StiffnessKind::Notch => "notch",
        StiffnessKind::Pocket => "pocket",
        StiffnessKind::Step => "step",
        StiffnessKind::Chamfer => "chamfer",
        StiffnessKind::Fillet => "fillet",
    }
}

/// The JSON name of a role.
pub fn role_name(r: WallRole) -> &'static str {
    match r {
        WallRole::Web => "web",
        WallRole::Rib => "rib",
        WallRole::Flange => "flange",
    }
}

/// `{"features": [...], "connections": [...]}` as documented in docs/CLI.md.
pub fn to_json(r: &Recognition, brep: &Brep) -> serde_json::Value {
    json!({
        "features": features_json(&r.features, brep),
        "connections": connections_json(&r.connections),
    })
}

/// The stiffness features as JSON objects (docs/CLI.md, `recognize --json`).
pub fn features_json(features: &[thinplan_plan::StiffnessFeature], brep: &Brep) -> Vec<Value> {
    features
        .iter()
        .map(|f| {
            let names: Vec<&str> = f
                .faces
                .iter()
                .map(|&i| brep.faces.get(i).map(|x| x.name.as_str()).unwrap_or(""))
                .collect();
            json!({
                "id": f.id.to_string(),
                "kind": kind_name(f.kind),
                "role": f.role.map(role_name),
                "thickness": f.thickness.map(r6),
                "height": r6(f.height),
                "length": r6(f.length),
                "axis": vec3(f.axis),
                "faces": f.faces,
                "face_names": names,
                "diameter": f.diameter.map(r6),
                "access": f.access.iter().map(|d| vec3(*d)).collect::<Vec<_>>(),
            })
        })
        .collect()
}

/// The connections as JSON objects (docs/CLI.md, `recognize --json`).
pub fn connections_json(connections: &[thinplan_plan::Connection]) -> Vec<Value> {
    connections
        .iter()
        .map(|c| {
            json!({
                "base": c.base.to_string(),
                "leaf": c.leaf.to_string(),
                "kind": match c.kind {
                    ConnectionKind::BaseLeaf => "base_leaf",
                    ConnectionKind::Crossing => "crossing",
                },
            })
        })
        .collect()
}

/// Fill colour of a feature by kind and role.
fn colour(kind: StiffnessKind, role: Option<WallRole>, i: usize) -> (f64, f64, f64) {
    let (h, s, l) = match (kind, role) {
        (StiffnessKind::Wall, Some(WallRole::Web)) => (210.0, 45.0, 70.0),
        (StiffnessKind::Wall, Some(WallRole::Flange)) => (30.0, 75.0, 60.0),
        (StiffnessKind::Wall, _) => (130.0, 45.0, 55.0),
        (StiffnessKind::Hole, _) => (0.0, 70.0, 55.0),
        (StiffnessKind::Cutout, _) => (300.0, 55.0, 60.0),
        (StiffnessKind::Slot, _) => (270.0, 50.0, 60.0),
        (StiffnessKind::Pocket, _) => (50.0, 80.0, 55.0),
        (StiffnessKind::Fillet, _) | (StiffnessKind::Chamfer, _) => (180.0, 40.0, 60.0),
        _ => (340.0, 50.0, 60.0),
    };
    // Vary the lightness a little so neighbouring features differ.
    let l = l + ((i % 4) as f64 - 1.5) * 4.0;
    (h, s, l)
}

fn hsl((h, s, l): (f64, f64, f64), shade: f64) -> String {
    format!("hsl({h:.0},{s:.0}%,{:.0}%)", l * shade)
}

/// A picture of the part (isometric projection of the tessellation, faces
/// coloured by their feature, unclaimed faces grey, shaded by the normal)
/// and the connection graph beside it (nodes by id, arrows base → leaf,
/// dashed lines for crossings). Deterministic bytes.
pub fn to_svg(r: &Recognition, brep: &Brep) -> String {
    let bbox = brep.rough_bbox();
    let diag = bbox.extent().length().max(1e-9);
    let mesh = thinplan_brep::tessellate(brep, &TessTolerance::relative(diag, 2e-3));
    // Isometric view direction (from the viewer towards the part).
    let view = DVec3::new(-1.0, -1.0, -1.0).normalize();
    let right = DVec3::new(1.0, -1.0, 0.0).normalize();
    let upv = right.cross(view).normalize();
    let proj = |p: DVec3| DVec2::new(p.dot(right), -p.dot(upv));

    let mut owner: BTreeMap<usize, usize> = BTreeMap::new();
    for (fi, f) in r.features.iter().enumerate() {
        for &face in &f.faces {
            // Walls first (they come first in id order); keep the first owner
            // except that depressions paint over the walls they are in.
            let e = owner.entry(face).or_insert(fi);
            if r.features[*e].kind == StiffnessKind::Wall && f.kind != StiffnessKind::Wall {
                *e = fi;
            }
        }
    }
    let colours: Vec<(f64, f64, f64)> = r
        .features
        .iter()
        .enumerate()
        .map(|(i, f)| colour(f.kind, f.role, i))
        .collect();

    // Triangles facing the viewer, painter-sorted by depth.
    let mut tris: Vec<(f64, usize, [DVec2; 3], f64)> = Vec::new();
    let max_edge = diag / 25.0;
    for (ti, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        if n.dot(view) >= 0.0 {
            continue;
        }
        let shade = 0.55 + 0.45 * (-n.normalize().dot(view)).clamp(0.0, 1.0);
        // Long triangles (fans across a web) defeat painter's sorting by
        // centroid; split them until no edge exceeds a fraction of the part.
        let mut stack = vec![([a, b, c], 0u32)];
        while let Some(([a, b, c], level)) = stack.pop() {
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            if longest > max_edge && level < 4 {
                let (ab, bc, ca) = ((a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0);
                stack.extend([
                    ([a, ab, ca], level + 1),
                    ([ab, b, bc], level + 1),
                    ([ca, bc, c], level + 1),
                    ([ab, bc, ca], level + 1),
                ]);
                continue;
            }
            let depth = ((a + b + c) / 3.0).dot(view);
            tris.push((depth, ti, [proj(a), proj(b), proj(c)], shade));
        }
    }
    // Stable for equal keys, so sub-triangles keep their push order.
    tris.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));

    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in &mesh.positions {
        let q = proj(*p);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    if !lo.x.is_finite() {
        lo = DVec2::ZERO;
        hi = DVec2::ONE;
    }
    let size = 600.0;
    let scale = size / (hi - lo).max_element().max(1e-9);
    let pad = 20.0;
    let map = |p: DVec2| (p - lo) * scale + DVec2::splat(pad);
    let graph_x = size + 3.0 * pad;
    let graph_w = 420.0;
    let width = graph_x + graph_w + pad;
    let height = size + 2.0 * pad;

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="sans-serif" font-size="11">"#,
        w = width,
        h = height.max(graph_height(r) + 2.0 * pad)
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<g id="part" stroke-width="0.3" stroke-linejoin="round">"#
    );
    for (_, ti, p, shade) in &tris {
        let face = mesh.face_of_triangle[*ti];
        let fill = match owner.get(&face) {
            Some(&fi) => hsl(colours[fi], *shade),
            None => hsl((0.0, 0.0, 85.0), *shade),
        };
        let q = p.map(map);
        let _ = writeln!(
            s,
            r#"<path d="M{:.2} {:.2}L{:.2} {:.2}L{:.2} {:.2}Z" fill="{fill}" stroke="{fill}"/>"#,
            q[0].x, q[0].y, q[1].x, q[1].y, q[2].x, q[2].y
        );
    }
    let _ = writeln!(s, "</g>");

    // The connection graph: nodes in layers by depth from the roots.
    let pos = graph_layout(r, graph_x, pad, graph_w);
    let _ = writeln!(
        s,
        r#"<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" markerHeight="7" orient="auto"><path d="M0 0L10 5L0 10Z" fill="black"/></marker></defs>"#
    );
    let _ = writeln!(
        s,
        r#"<g id="graph" stroke="black" stroke-width="1.2" fill="none">"#
    );
    for c in &r.connections {
        let (Some(a), Some(b)) = (pos.get(&c.base.0), pos.get(&c.leaf.0)) else {
            continue;
        };
        let d = (*b - *a).normalize_or_zero();
        let (p, q) = (*a + d * 14.0, *b - d * 14.0);
        match c.kind {
            ConnectionKind::BaseLeaf => {
                let _ = writeln!(
                    s,
                    r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" marker-end="url(#arrow)"/>"#,
                    p.x, p.y, q.x, q.y
                );
            }
            ConnectionKind::Crossing => {
                let _ = writeln!(
                    s,
                    r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke-dasharray="4 3"/>"#,
                    p.x, p.y, q.x, q.y
                );
            }
        }
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(s, r#"<g id="nodes" text-anchor="middle">"#);
    for (fi, f) in r.features.iter().enumerate() {
        let Some(p) = pos.get(&f.id.0) else { continue };
        let label = match f.role {
            Some(role) => role_name(role),
            None => kind_name(f.kind),
        };
        let _ = writeln!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="13" fill="{}" stroke="black"/><text x="{:.1}" y="{:.1}">{}</text><text x="{:.1}" y="{:.1}" font-size="8" fill="dimgray">{}</text>"#,
            p.x,
            p.y,
            hsl(colours[fi], 1.0),
            p.x,
            p.y + 4.0,
            f.id,
            p.x,
            p.y + 23.0,
            label
        );
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(s, "</svg>");
    s
}

fn graph_height(r: &Recognition) -> f64 {
    let layers = layers(r);
    let max_layer = layers.values().copied().max().unwrap_or(0);
    (max_layer as f64 + 1.0) * 70.0
}

/// Layer of each feature id: 0 for features that are no leaf of a
/// base–leaf connection, else one more than the deepest base (bounded).
fn layers(r: &Recognition) -> BTreeMap<u32, usize> {
    let mut layer: BTreeMap<u32, usize> = r.features.iter().map(|f| (f.id.0, 0)).collect();
    for _ in 0..r.features.len().min(64) {
        let mut changed = false;
        for c in &r.connections {
            if c.kind != ConnectionKind::BaseLeaf {
                continue;
            }
            let lb = layer.get(&c.base.0).copied().unwrap_or(0);
            if let Some(l) = layer.get_mut(&c.leaf.0) {
                if *l < lb + 1 && lb < 63 {
                    *l = lb + 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    layer
}

fn graph_layout(r: &Recognition, x0: f64, y0: f64, w: f64) -> BTreeMap<u32, DVec2> {
    let layer = layers(r);
    let mut rows: BTreeMap<usize, Vec<u32>> = BTreeMap::new();
    for (id, l) in &layer {
        rows.entry(*l).or_default().push(*id);
    }
    let mut out = BTreeMap::new();
    for (l, ids) in rows {
        let n = ids.len();
        for (i, id) in ids.into_iter().enumerate() {
            let x = x0 + w * (i as f64 + 0.5) / n as f64;
            // Stagger crowded rows so labels do not overlap.
            let stagger = if n > 12 && i % 2 == 1 { 30.0 } else { 0.0 };
            let y = y0 + 20.0 + l as f64 * 70.0 + stagger;
            out.insert(id, DVec2::new(x, y));
        }
    }
    out
}
