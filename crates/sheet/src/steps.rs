//! One wall's machining features in a section across the wall, numbered in
//! the order they are machined (thesis figure 4.1): the large features of
//! height H on one side, the small ones of height h on the other, taken
//! alternately top-down. Needs only stage 5 (and 6) of the plan, so
//! `thinplan plan --until features --svg DIR` can draw it.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use glam::DVec2;
use thinplan_plan::{Plan, StiffnessFeatureId};

use crate::section::{self, Canvas, Section};
use crate::{escape, num, owner_colour};

/// What a feature is, from the knowledge block that made it.
fn kind_of(f: &thinplan_plan::MachiningFeature) -> String {
    let rule = &f.origin.rule;
    match f.origin.large {
        Some(l) if rule.ends_with("wall_steps") => (if l { "large" } else { "small" }).to_string(),
        _ => rule
            .rsplit('.')
            .next()
            .unwrap_or_default()
            .replace('_', " "),
    }
}

/// The figure-4.1 picture for the wall `owner`: the wall (dark) and each of
/// its machining features as its box in the section, with its place in the
/// plan's machining order among this wall's features (1 is machined first)
/// and its id; a legend lists them in that order with their depths.
pub fn wall_steps_svg(plan: &Plan, owner: StiffnessFeatureId) -> String {
    let section = Section::of(plan, owner);
    let order: Vec<_> = plan
        .machining_order()
        .into_iter()
        .filter(|id| section.features.iter().any(|(f, ..)| f.id == *id))
        .collect();
    let place = |id| order.iter().position(|o| *o == id).map_or(0, |i| i + 1);

    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for (a, b) in section
        .wall
        .iter()
        .copied()
        .chain(section.features.iter().map(|(_, a, b)| (*a, *b)))
    {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let c = Canvas::fit(lo, hi, (60.0, 300.0, 50.0, 30.0), 1100.0, 640.0);
    let (w_px, h_px, mr, mt, mb) = (c.w_px, c.h_px, c.mr, c.mt, c.mb);
    let map = |p: DVec2| c.map(p);
    let title = section.title(
        owner,
        &format!(
            "{} machining feature(s) in a section across the wall, numbered in machining order",
            order.len()
        ),
    );
    let mut s = String::new();
    section::frame(&mut s, &c, &title, section.n);
    let colour = owner_colour(owner);
    // Pieces of one feature along the wall (stage 6 splits) share a box in
    // the section: one box, all their places.
    let mut boxes: BTreeMap<[i64; 4], Vec<&thinplan_plan::MachiningFeature>> = BTreeMap::new();
    for (f, a, b) in &section.features {
        let key = [a.x, a.y, b.x, b.y].map(|c| (c * 1000.0).round() as i64);
        boxes.entry(key).or_default().push(f);
    }
    for (key, feats) in &boxes {
        let [a, b] = [
            DVec2::new(key[0] as f64, key[1] as f64) / 1000.0,
            DVec2::new(key[2] as f64, key[3] as f64) / 1000.0,
        ];
        let (pa, pb) = (map(a), map(b));
        let f = feats[0];
        let opacity = match kind_of(f).as_str() {
            "large" => "0.35",
            "small" => "0.15",
            _ => "0.08",
        };
        let c = 0.5 * (pa + pb);
        let mut places: Vec<usize> = feats.iter().map(|f| place(f.id)).collect();
        places.sort_unstable();
        let label = ranges(&places);
        let ids = match feats.len() {
            1 => f.id.to_string(),
            n => format!("{} +{}", f.id, n - 1),
        };
        let _ = writeln!(
            s,
            "<g><title>{} — {} (place {label})</title><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{colour}\" fill-opacity=\"{opacity}\" stroke=\"{colour}\"/><text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"{}\" font-weight=\"bold\">{label}</text><text x=\"{}\" y=\"{}\" fill=\"{colour}\" font-size=\"9\">{ids}</text></g>",
            feats.iter().map(|f| f.id.to_string()).collect::<Vec<_>>().join(" "),
            escape(&kind_of(f)),
            num(pa.x, 2),
            num(pb.y, 2),
            num(pb.x - pa.x, 2),
            num(pa.y - pb.y, 2),
            num(c.x, 2),
            num(c.y + 5.0, 2),
            num(((pa.y - pb.y) * 0.6).clamp(9.0, 16.0), 1),
            num(pa.x + 2.0, 2),
            num(pb.y + 10.0, 2),
        );
    }
    if let Some((a, b)) = section.wall {
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
    // Legend: the features in machining order.
    let lx = w_px - mr + 14.0;
    let mut ly = mt + 10.0;
    let _ = writeln!(s, "<g font-size=\"11\">");
    for line in [
        "in machining order (1 first):".to_string(),
        "place  feature  kind  height along up, mm".to_string(),
    ] {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">{}</text>",
            num(lx, 1),
            num(ly, 1),
            escape(&line)
        );
        ly += 15.0;
    }
    for (k, id) in order.iter().enumerate() {
        if ly > h_px - mb {
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\">… {} more</text>",
                num(lx, 1),
                num(ly, 1),
                order.len() - k
            );
            break;
        }
        let Some((f, a, b)) = section.features.iter().find(|(f, ..)| f.id == *id) else {
            continue;
        };
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">{}.  {}  {}  {} – {}</text>",
            num(lx, 1),
            num(ly, 1),
            k + 1,
            f.id,
            escape(&kind_of(f)),
            num(a.y, 2),
            num(b.y, 2)
        );
        ly += 14.0;
    }
    s.push_str("</g>\n</svg>\n");
    s
}

/// "1, 3–5, 8" for [1, 3, 4, 5, 8].
fn ranges(sorted: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        parts.push(if j > i {
            format!("{}–{}", sorted[i], sorted[j])
        } else {
            sorted[i].to_string()
        });
        i = j + 1;
    }
    parts.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(name: &str) -> Plan {
        let k = thinplan_pipeline::load_knowledge(None).unwrap();
        let setup =
            thinplan_pipeline::make_setup(&thinplan_pipeline::SetupRequest::default(), &k).unwrap();
        let mut s = thinplan_pipeline::Session::open(&format!("builtin:{name}"), setup, k).unwrap();
        s.run_to(
            thinplan_plan::Stage::Resolve,
            &std::sync::atomic::AtomicBool::new(false),
            |_| {},
        )
        .unwrap();
        s.plan
    }

    /// Reads back "place. MFn" from the legend.
    fn legend(svg: &str) -> Vec<(usize, String)> {
        svg.lines()
            .filter_map(|l| {
                let t = l.split('>').nth(1)?.split('<').next()?;
                let (k, rest) = t.split_once(".  ")?;
                Some((k.parse().ok()?, rest.split("  ").next()?.to_string()))
            })
            .collect()
    }

    #[test]
    fn tall_ribs_picture_numbers_its_eight_features_in_an_order_the_constraints_allow() {
        let plan = planned("tall_rib");
        let rib = plan
            .stiffness_features
            .iter()
            .find(|f| f.role == Some(thinplan_plan::WallRole::Rib))
            .unwrap();
        let svg = wall_steps_svg(&plan, rib.id);
        let listed = legend(&svg);
        let mine: Vec<_> = plan
            .machining_features
            .iter()
            .filter(|f| f.owner == rib.id)
            .collect();
        assert_eq!(listed.len(), mine.len(), "{svg}");
        assert_eq!(
            listed.iter().map(|(k, _)| *k).collect::<Vec<_>>(),
            (1..=mine.len()).collect::<Vec<_>>()
        );
        // Every constraint between two of them is honoured by the numbers.
        let place = |id: thinplan_plan::MachiningFeatureId| {
            listed
                .iter()
                .find(|(_, s)| *s == id.to_string())
                .map(|(k, _)| *k)
                .unwrap()
        };
        let mut checked = 0;
        for c in &plan.machining_constraints {
            if mine.iter().any(|f| f.id == c.first) && mine.iter().any(|f| f.id == c.second) {
                assert!(place(c.first) < place(c.second), "{} {}", c.first, c.second);
                checked += 1;
            }
        }
        assert!(checked >= 7, "{checked}");
        // One box per feature plus the wall; valid enough for a viewer.
        assert_eq!(svg.matches("<rect ").count(), 1 + mine.len() + 1);
        assert_eq!(ranges(&[1, 3, 4, 5, 8]), "1, 3–5, 8");
        assert!(svg.starts_with("<svg ") && svg.trim_end().ends_with("</svg>"));
    }
}
