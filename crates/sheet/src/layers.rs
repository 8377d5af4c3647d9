//! One wall's operation layers in a section across the wall (thesis figure
//! 7.9): every pass of the operations of the wall's machining features at
//! its tool-centre offset from the wall and its z-level, coloured by region
//! (boundary / full cut / rest), with the direction along the wall (towards
//! or away from the viewer) so alternating layers show.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use glam::{DVec2, DVec3};
use thinplan_plan::{Plan, Region3, StiffnessFeatureId};

use crate::section::{self, Canvas, Section};
use crate::{escape, num, owner_colour};

fn region_colour(r: Region3) -> &'static str {
    match r {
        Region3::Boundary => "#d62728",
        Region3::FullCut => "#ff7f0e",
        Region3::Rest => "#1f77b4",
        Region3::Rapid | Region3::Link => "#999999",
    }
}

fn region_name(r: Region3) -> &'static str {
    match r {
        Region3::Boundary => "boundary",
        Region3::FullCut => "full cut",
        Region3::Rest => "rest",
        Region3::Rapid => "rapid",
        Region3::Link => "link",
    }
}

/// A pass along the wall, seen in the section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct PassKey {
    /// Offset from the wall's mid-plane and height, µm.
    s: i64,
    h: i64,
    region: u8,
    /// +1: along +w (towards the viewer), −1 away.
    dir: i8,
}

fn region_index(r: Region3) -> u8 {
    match r {
        Region3::Boundary => 0,
        Region3::FullCut => 1,
        Region3::Rest => 2,
        Region3::Rapid => 3,
        Region3::Link => 4,
    }
}

const REGIONS: [Region3; 5] = [
    Region3::Boundary,
    Region3::FullCut,
    Region3::Rest,
    Region3::Rapid,
    Region3::Link,
];

/// The figure-7.9 picture for the wall `feature_owner`: a section across
/// the wall (horizontal: offset along the wall's normal from its
/// mid-plane; vertical: height along up), the wall and its machining
/// features (dashed, by id), and every move of their operations projected
/// onto that plane. Passes along the wall are marked at their tool centre —
/// ⊙ coming towards the viewer, ⊗ going away — with a faint bar of the
/// tool's width; moves across the wall (entries, stepovers) are lines.
/// A wall with no operations gives a picture that says so.
pub fn layers_svg(plan: &Plan, feature_owner: StiffnessFeatureId) -> String {
    let section = Section::of(plan, feature_owner);
    let Section { n, w, wall, .. } = section;
    let sh = |p: DVec3| section.at(p);
    let (w_max, h_px) = (1000.0, 640.0);
    let feats: Vec<&thinplan_plan::MachiningFeature> =
        section.features.iter().map(|(f, ..)| *f).collect();
    let feat_boxes: Vec<_> = section
        .features
        .iter()
        .map(|(f, a, b)| (f.id, *a, *b))
        .collect();
    let ops: Vec<&thinplan_plan::Operation> = plan
        .operation_order
        .iter()
        .filter_map(|id| plan.operations.iter().find(|o| o.id == *id))
        .filter(|o| feats.iter().any(|f| f.id == o.feature))
        .collect();

    let mut passes: BTreeMap<PassKey, f64> = BTreeMap::new(); // → tool radius
    let mut lines: Vec<(DVec2, DVec2, Region3)> = Vec::new();
    for op in &ops {
        let radius = 0.5
            * op.provenance
                .values
                .get("tool_diameter_mm")
                .copied()
                .unwrap_or(0.0);
        let mut prev = op.start;
        for mv in &op.moves {
            let pts = match &mv.arc {
                Some(a) => {
                    thinplan_post::linearise_arc(prev, mv.to, a.centre, a.axis, a.clockwise, 0.01)
                }
                None => vec![mv.to],
            };
            let mut a = prev;
            for b in pts {
                let (pa, pb) = (sh(a), sh(b));
                let dt = (b - a).dot(w);
                let cutting = !matches!(mv.region, Region3::Rapid | Region3::Link);
                if cutting && dt.abs() > 1e-9 && dt.abs() >= (pb - pa).length() {
                    let m = 0.5 * (pa + pb);
                    passes.insert(
                        PassKey {
                            s: (m.x * 1000.0).round() as i64,
                            h: (m.y * 1000.0).round() as i64,
                            region: region_index(mv.region),
                            dir: if dt > 0.0 { 1 } else { -1 },
                        },
                        radius,
                    );
                } else if (pb - pa).length() > 1e-6 {
                    lines.push((pa, pb, mv.region));
                }
                a = b;
            }
            prev = mv.to;
        }
    }

    // Extent of the picture.
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    let mut grow = |p: DVec2| {
        lo = lo.min(p);
        hi = hi.max(p);
    };
    if let Some((a, b)) = wall {
        grow(a);
        grow(b);
    }
    for (_, a, b) in &feat_boxes {
        grow(*a);
        grow(*b);
    }
    for (k, r) in &passes {
        let p = DVec2::new(k.s as f64 / 1000.0, k.h as f64 / 1000.0);
        grow(p - DVec2::new(*r, 0.0));
        grow(p + DVec2::new(*r, 0.0));
    }
    let c = Canvas::fit(lo, hi, (60.0, 240.0, 50.0, 40.0), w_max, h_px);
    let (w_px, scale, mr, mt) = (c.w_px, c.scale, c.mr, c.mt);
    let map = |p: DVec2| c.map(p);
    let title = section.title(
        feature_owner,
        &format!(
            "operation layers in a section across the wall ({} operation(s))",
            ops.len()
        ),
    );
    let mut s = String::new();
    section::frame(&mut s, &c, &title, n);
    // Machining features.
    for (id, a, b) in &feat_boxes {
        let (pa, pb) = (map(*a), map(*b));
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{c}\" fill-opacity=\"0.06\" stroke=\"{c}\" stroke-dasharray=\"5 3\"/><text x=\"{}\" y=\"{}\" fill=\"{c}\" font-size=\"10\">{id}</text>",
            num(pa.x, 2),
            num(pb.y, 2),
            num(pb.x - pa.x, 2),
            num(pa.y - pb.y, 2),
            num(pa.x + 2.0, 2),
            num(pb.y + 11.0, 2),
            c = owner_colour(feature_owner)
        );
    }
    // The wall.
    if let Some((a, b)) = wall {
        let (pa, pb) = (map(a), map(b));
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#444\"/>",
            num(pa.x, 2),
            num(pb.y, 2),
            num((pb.x - pa.x).max(1.0), 2),
            num(pa.y - pb.y, 2)
        );
    }
    // Moves across the wall.
    for (a, b, r) in &lines {
        let (pa, pb) = (map(*a), map(*b));
        let link = matches!(r, Region3::Rapid | Region3::Link);
        let _ = writeln!(
            s,
            "<path d=\"M{} {} L{} {}\" stroke=\"{}\" stroke-width=\"{}\"{}/>",
            num(pa.x, 2),
            num(pa.y, 2),
            num(pb.x, 2),
            num(pb.y, 2),
            region_colour(*r),
            if link { "0.6" } else { "1.2" },
            if link {
                " stroke-dasharray=\"2 2\""
            } else {
                ""
            }
        );
    }
    // Passes: the tool's width faint, the centre marked with its direction.
    let mr_px = 4.5;
    for (k, r) in &passes {
        let region = REGIONS[k.region as usize];
        let c = map(DVec2::new(k.s as f64 / 1000.0, k.h as f64 / 1000.0));
        let half = r * scale;
        let col = region_colour(region);
        let _ = writeln!(
            s,
            "<path d=\"M{} {} H{}\" stroke=\"{col}\" stroke-opacity=\"0.18\" stroke-width=\"3\"/>",
            num(c.x - half, 2),
            num(c.y, 2),
            num(c.x + half, 2)
        );
        let mark = if k.dir > 0 {
            format!(
                "<circle cx=\"{x}\" cy=\"{y}\" r=\"1.4\" fill=\"{col}\"/>",
                x = num(c.x, 2),
                y = num(c.y, 2)
            )
        } else {
            let d = mr_px * 0.7;
            format!(
                "<path d=\"M{} {} L{} {} M{} {} L{} {}\" stroke=\"{col}\" stroke-width=\"1.2\"/>",
                num(c.x - d, 2),
                num(c.y - d, 2),
                num(c.x + d, 2),
                num(c.y + d, 2),
                num(c.x - d, 2),
                num(c.y + d, 2),
                num(c.x + d, 2),
                num(c.y - d, 2)
            )
        };
        let _ = writeln!(
            s,
            "<g><title>{} pass at offset {} mm, z {} mm</title><circle cx=\"{}\" cy=\"{}\" r=\"{mr_px}\" fill=\"white\" stroke=\"{col}\" stroke-width=\"1.2\"/>{mark}</g>",
            region_name(region),
            num(k.s as f64 / 1000.0, 3),
            num(k.h as f64 / 1000.0, 3),
            num(c.x, 2),
            num(c.y, 2)
        );
    }
    // Legend.
    let lx = w_px - mr + 14.0;
    let mut ly = mt + 10.0;
    let _ = writeln!(s, "<g font-size=\"12\">");
    for r in [Region3::Boundary, Region3::FullCut, Region3::Rest] {
        let n_r = passes
            .keys()
            .filter(|k| REGIONS[k.region as usize] == r)
            .count();
        let _ = writeln!(
            s,
            "<circle cx=\"{}\" cy=\"{}\" r=\"{mr_px}\" fill=\"white\" stroke=\"{}\" stroke-width=\"1.2\"/><text x=\"{}\" y=\"{}\">{} ({n_r})</text>",
            num(lx, 1),
            num(ly, 1),
            region_colour(r),
            num(lx + 10.0, 1),
            num(ly + 4.0, 1),
            region_name(r)
        );
        ly += 18.0;
    }
    let _ = writeln!(
        s,
        "<path d=\"M{} {} h14\" stroke=\"#999\" stroke-dasharray=\"2 2\"/><text x=\"{}\" y=\"{}\">link / rapid</text>",
        num(lx - 7.0, 1),
        num(ly, 1),
        num(lx + 10.0, 1),
        num(ly + 4.0, 1)
    );
    ly += 24.0;
    for line in [
        "⊙ pass towards the viewer",
        "⊗ pass away from the viewer",
        "faint bar: tool width",
        "dark: the wall",
        "dashed: its machining features",
    ] {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">{}</text>",
            num(lx - 7.0, 1),
            num(ly, 1),
            escape(line)
        );
        ly += 16.0;
    }
    s.push_str("</g>\n</svg>\n");
    s
}
