//! The shop-floor setup sheet: one self-contained HTML
//! page per plan — inline CSS and SVG, no scripts, no external resources —
//! with the part, the set-up, the blank, the tools with their tool-table
//! numbers, the sequence of machining features per wall, the operations in
//! order with their times and the total, and what a planner must see
//! (refusals, warnings, holder and shank collisions). Also the wall-layers
//! picture of thesis figure 7.9 ([`layers_svg`]).
//!
//! Deterministic bytes: numbers have fixed decimals, everything is iterated
//! in id or plan order. All text from the plan and knowledge is escaped.

mod layers;
mod section;
mod steps;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use glam::{DVec2, DVec3};
use thinplan_brep::Brep;
use thinplan_collision::{Body, ToolPart};
use thinplan_knowledge::Knowledge;
use thinplan_plan::{MachiningFeatureId, OperationId, Plan, StiffnessFeatureId};

pub use layers::layers_svg;
pub use steps::wall_steps_svg;

/// Text for HTML and SVG: `&`, `<`, `>`, `"` and `'` escaped.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            // Control characters have no place in a page.
            c if c.is_control() && c != '\n' && c != '\t' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// `v` with `d` decimals, never `-0.0`, `-` for a value that is not finite.
pub fn num(v: f64, d: usize) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let s = format!("{v:.d$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

/// A colour per owner (stiffness feature), the same on every picture.
pub fn owner_colour(owner: StiffnessFeatureId) -> &'static str {
    const PALETTE: [&str; 10] = [
        "#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2",
        "#bcbd22", "#7f7f7f",
    ];
    PALETTE[owner.0 as usize % PALETTE.len()]
}

fn vec3(v: DVec3) -> String {
    format!("({}, {}, {})", num(v.x, 3), num(v.y, 3), num(v.z, 3))
}

/// Minutes and seconds, e.g. `2 min 05.3 s`.
fn min_s(t: f64) -> String {
    if !t.is_finite() || t < 0.0 {
        return num(t, 1);
    }
    let m = (t / 60.0).floor();
    format!("{} min {:0>4} s", m as u64, num(t - 60.0 * m, 1))
}

/// The total of the operations' times in the plan's order, s.
pub fn total_time(plan: &Plan) -> f64 {
    plan.operation_order
        .iter()
        .filter_map(|id| plan.operations.iter().find(|o| o.id == *id))
        .map(|o| thinplan_operations::summary(o).time_s)
        .sum()
}

/// The setup sheet with the plan's own refusals only.
pub fn setup_sheet(plan: &Plan, k: &Knowledge, brep: &Brep) -> String {
    setup_sheet_with_warnings(plan, k, brep, &[])
}

/// Writes the setup sheet atomically (the CLI's `plan --sheet FILE`).
pub fn write_sheet(
    path: &Path,
    plan: &Plan,
    k: &Knowledge,
    brep: &Brep,
    warnings: &[String],
) -> Result<(), String> {
    let html = setup_sheet_with_warnings(plan, k, brep, warnings);
    thinplan_plan::io::write_atomic(path, html.as_bytes())
        .map_err(|e| format!("{}: cannot write the setup sheet: {e}", path.display()))
}

const CSS: &str = "body{font-family:sans-serif;margin:1.5em;color:#111}\
h1{font-size:1.4em}h2{font-size:1.15em;border-bottom:1px solid #999;margin-top:1.6em}\
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;padding:2px 6px;text-align:left;vertical-align:top}\
th{background:#eee}td.n{text-align:right;font-variant-numeric:tabular-nums}\
tr.total td{font-weight:bold;background:#f4f4f4}.warn{color:#a40}.bad{color:#b00;font-weight:bold}\
pre{background:#f6f6f6;padding:.5em;border:1px solid #ddd}.sw{display:inline-block;width:.9em;height:.9em;vertical-align:middle;margin-right:.3em}\
@media print{h2{page-break-after:avoid}table{page-break-inside:auto}}";

/// The setup sheet, with the warnings of the stages that ran (the
/// pipeline's `Session::warnings`).
pub fn setup_sheet_with_warnings(
    plan: &Plan,
    k: &Knowledge,
    brep: &Brep,
    warnings: &[String],
) -> String {
    let mut h = String::new();
    let title = format!("Setup sheet — {}", plan.part.source);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{CSS}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
        escape(&title),
        escape(&title)
    );
    let tools = k.tool_set(&plan.setup.tool_set);
    let tool_no = |id: &str| -> Option<usize> {
        tools.and_then(|t| t.tools.iter().position(|x| x.id == id).map(|i| i + 1))
    };
    let frame = thinplan_collision::setup_frame(plan.setup.up);
    let part = thinplan_collision::part_bodies(brep, &frame);

    verification(&mut h, plan);

    // Part and set-up.
    let p = &plan.part;
    h.push_str("<h2>Part and set-up</h2>\n<table>\n");
    let row = |h: &mut String, k: &str, v: &str| {
        let _ = writeln!(h, "<tr><th>{}</th><td>{}</td></tr>", escape(k), escape(v));
    };
    row(&mut h, "part", &p.source);
    row(&mut h, "format", &format!("{:?}", p.format).to_lowercase());
    row(&mut h, "SHA-256", &p.sha256);
    row(&mut h, "declared units", &p.declared_units);
    row(
        &mut h,
        "solids / faces",
        &format!("{} / {}", p.summary.solids, p.summary.faces),
    );
    row(
        &mut h,
        "volume",
        &format!("{} mm³", num(p.summary.volume, 1)),
    );
    row(
        &mut h,
        "up (spindle axis, part coordinates)",
        &vec3(plan.setup.up),
    );
    row(
        &mut h,
        "set-up frame x / y",
        &format!("{} / {}", vec3(frame.x), vec3(frame.y)),
    );
    let machine = k
        .machine(&plan.setup.machine)
        .map_or(String::new(), |m| format!(" — {}", m.name));
    row(
        &mut h,
        "machine",
        &format!("{}{machine}", plan.setup.machine),
    );
    let set_name = tools.map_or(" (not in the knowledge)".into(), |t| {
        format!(" — {}", t.name)
    });
    row(
        &mut h,
        "tool set",
        &format!("{}{set_name}", plan.setup.tool_set),
    );
    let mat = k
        .material(&plan.setup.material)
        .map_or(String::new(), |m| format!(" — {}", m.name));
    row(&mut h, "material", &format!("{}{mat}", plan.setup.material));
    row(
        &mut h,
        "knowledge",
        plan.notes.get("knowledge").map_or(k.origin.as_str(), |s| s),
    );
    if let Some(v) = plan.notes.get("thinplan_version") {
        row(&mut h, "thinplan", v);
    }
    let stages: Vec<String> = plan
        .stages_done
        .iter()
        .map(|s| format!("{s:?}").to_lowercase())
        .collect();
    row(&mut h, "stages done", &stages.join(", "));
    h.push_str("</table>\n");

    // Blank.
    let (lo, hi) = blank(&part);
    h.push_str("<h2>Blank</h2>\n<p>The part's box in the set-up frame (x, y as above, z along up), mm.</p>\n<table>\n<tr><th></th><th>x</th><th>y</th><th>z</th></tr>\n");
    for (name, v) in [("min", lo), ("max", hi), ("size", hi - lo)] {
        let _ = writeln!(
            h,
            "<tr><th>{name}</th><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>",
            num(v.x, 3),
            num(v.y, 3),
            num(v.z, 3)
        );
    }
    h.push_str("</table>\n");
    if let Some(v) = plan.notes.get("resolve.blank_volume") {
        let _ = writeln!(
            h,
            "<p>Blank volume {} mm³; to remove {} mm³.</p>",
            escape(v),
            escape(plan.notes.get("resolve.features_volume").map_or("–", |s| s))
        );
    }
    h.push_str(&top_view(plan, &frame, &part, lo, hi));

    // Tools.
    h.push_str("<h2>Tools</h2>\n");
    let mut uses: BTreeMap<&str, usize> = BTreeMap::new();
    for o in &plan.operations {
        *uses.entry(o.tool.as_str()).or_default() += 1;
    }
    match tools {
        Some(set) => {
            h.push_str("<table>\n<tr><th>T</th><th>tool</th><th>kind</th><th>Ø</th><th>corner r</th><th>flutes</th><th>flute length</th><th>stickout</th><th>shank Ø</th><th>holder Ø × length</th><th>operations</th></tr>\n");
            for (i, t) in set.tools.iter().enumerate() {
                let _ = writeln!(
                    h,
                    "<tr id=\"tool-T{n}\"><td>T{n}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{} × {}</td><td class=\"n\">{}</td></tr>",
                    escape(&t.id),
                    escape(&format!("{:?}", t.kind)),
                    num(t.diameter, 3),
                    num(t.corner_radius, 3),
                    t.flutes,
                    num(t.flute_length, 1),
                    num(t.stickout, 1),
                    num(t.shank_diameter, 1),
                    num(t.holder_diameter, 1),
                    num(t.holder_length, 1),
                    uses.get(t.id.as_str()).copied().unwrap_or(0),
                    n = i + 1,
                );
            }
            h.push_str("</table>\n<p>LinuxCNC tool table (lengths are measured at the machine):</p>\n<pre>");
            h.push_str(&escape(&thinplan_post::tool_table(set, 3)));
            h.push_str("</pre>\n");
        }
        None => {
            let _ = writeln!(
                h,
                "<p class=\"bad\">The knowledge has no tool set {}.</p>",
                escape(&plan.setup.tool_set)
            );
        }
    }

    // Operations per feature, in order.
    let ops: BTreeMap<OperationId, &thinplan_plan::Operation> =
        plan.operations.iter().map(|o| (o.id, o)).collect();
    let mut ops_of: BTreeMap<MachiningFeatureId, Vec<OperationId>> = BTreeMap::new();
    for id in &plan.operation_order {
        if let Some(o) = ops.get(id) {
            ops_of.entry(o.feature).or_default().push(*id);
        }
    }

    // The sequence of machining features per wall (owner).
    h.push_str("<h2>Machining features per wall</h2>\n<p>In the order they are machined (features no operation removes last); depth along up.</p>\n");
    let mut owners: Vec<StiffnessFeatureId> =
        plan.machining_features.iter().map(|f| f.owner).collect();
    owners.sort();
    owners.dedup();
    let position: BTreeMap<OperationId, usize> = plan
        .operation_order
        .iter()
        .enumerate()
        .map(|(i, id)| (*id, i))
        .collect();
    for owner in owners {
        let sf = plan.stiffness_features.iter().find(|s| s.id == owner);
        let what = sf.map_or(String::new(), |s| {
            let role = s
                .role
                .map_or(String::new(), |r| format!(" {r:?}").to_lowercase());
            format!("{:?}{role}", s.kind).to_lowercase()
        });
        let _ = writeln!(
            h,
            "<h3><span class=\"sw\" style=\"background:{}\"></span>{} {}</h3>",
            owner_colour(owner),
            owner,
            escape(&what)
        );
        let mut feats: Vec<&thinplan_plan::MachiningFeature> = plan
            .machining_features
            .iter()
            .filter(|f| f.owner == owner)
            .collect();
        feats.sort_by_key(|f| {
            let first = ops_of
                .get(&f.id)
                .and_then(|v| v.first())
                .and_then(|id| position.get(id))
                .copied()
                .unwrap_or(usize::MAX);
            (first, f.id)
        });
        h.push_str("<table>\n<tr><th>#</th><th>feature</th><th>top</th><th>bottom</th><th>volume mm³</th><th>sides</th><th>bottom</th><th>operations</th><th>rule</th><th>note</th></tr>\n");
        for (i, f) in feats.iter().enumerate() {
            let (top, bottom) = heights(f, &frame);
            let sides: Vec<String> = f
                .side_adjacency
                .iter()
                .map(|a| format!("{a:?}").to_lowercase())
                .collect();
            let op_ids = ops_of.get(&f.id).map_or(String::from("none"), |v| {
                v.iter()
                    .map(|o| o.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            });
            let volume = thinplan_collision::feature_body(f, &frame)
                .map_or(f64::NAN, |b| body_area(&b) * (b.z_hi - b.z_lo));
            let _ = writeln!(
                h,
                "<tr><td class=\"n\">{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td><td>{}</td><td{}>{}</td><td>{}</td><td>{}</td></tr>",
                i + 1,
                f.id,
                num(top, 3),
                num(bottom, 3),
                num(volume, 1),
                escape(&sides.join(" ")),
                escape(&format!("{:?}", f.bottom_adjacency).to_lowercase()),
                if ops_of.contains_key(&f.id) { "" } else { " class=\"bad\"" },
                escape(&op_ids),
                escape(&f.provenance.rule),
                escape(&f.provenance.note),
            );
        }
        h.push_str("</table>\n");
    }

    // Operations in order.
    h.push_str("<h2>Operations</h2>\n<table>\n<tr><th>#</th><th>operation</th><th>feature</th><th>wall</th><th>tool</th><th>pattern</th><th>layers</th><th>length mm</th><th>time s</th><th>spindle rpm</th><th>rule</th></tr>\n");
    let mut total = 0.0;
    let mut changes = 0;
    let mut last_tool: Option<&str> = None;
    for (i, id) in plan.operation_order.iter().enumerate() {
        let Some(o) = ops.get(id) else {
            let _ = writeln!(
                h,
                "<tr id=\"op-{id}\"><td class=\"n\">{}</td><td class=\"bad\" colspan=\"10\">{id}: in the order but not among the operations</td></tr>",
                i + 1
            );
            continue;
        };
        let s = thinplan_operations::summary(o);
        total += s.time_s;
        if last_tool != Some(o.tool.as_str()) {
            changes += 1;
            last_tool = Some(o.tool.as_str());
        }
        let owner = plan
            .machining_features
            .iter()
            .find(|f| f.id == o.feature)
            .map_or(String::new(), |f| f.owner.to_string());
        let t = tool_no(&o.tool).map_or(String::from("T?"), |n| format!("T{n}"));
        let _ = writeln!(
            h,
            "<tr id=\"op-{id}\"><td class=\"n\">{}</td><td>{id}</td><td>{}</td><td>{}</td><td>{} {}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
            i + 1,
            o.feature,
            escape(&owner),
            t,
            escape(&o.tool),
            escape(&s.pattern),
            s.layers,
            num(s.length_mm, 1),
            num(s.time_s, 1),
            num(o.spindle_rpm, 0),
            escape(&o.provenance.rule),
        );
    }
    let _ = writeln!(
        h,
        "<tr class=\"total\"><td colspan=\"8\">total: {} operation(s), {} tool change(s)</td><td class=\"n\" id=\"total-time\">{}</td><td colspan=\"2\">{}</td></tr>\n</table>",
        plan.operation_order.len(),
        changes,
        num(total, 1),
        min_s(total)
    );
    let unordered: Vec<String> = plan
        .operations
        .iter()
        .filter(|o| !position.contains_key(&o.id))
        .map(|o| o.id.to_string())
        .collect();
    if !unordered.is_empty() {
        let _ = writeln!(
            h,
            "<p class=\"bad\">Operations not in the order (not in the program): {}</p>",
            escape(&unordered.join(", "))
        );
    }

    // What a planner must see.
    h.push_str("<h2>Check before machining</h2>\n");
    let report = thinplan_collision::check(plan, k, brep);
    let mut by: BTreeMap<(OperationId, ToolPart, String), (usize, f64, usize)> = BTreeMap::new();
    for c in &report.collisions {
        let e = by
            .entry((c.operation, c.what, c.against.to_string()))
            .or_insert((0, 0.0, c.move_index));
        e.0 += 1;
        e.1 = f64::max(e.1, c.penetration);
    }
    let holders = report
        .collisions
        .iter()
        .filter(|c| c.what == ToolPart::Holder)
        .count();
    let _ = writeln!(
        h,
        "<h3>Holder and shank against the in-process stock</h3>\n<p id=\"collisions\"{}>{} collision(s) in {} move(s) checked piecewise ({} holder).</p>",
        if report.collisions.is_empty() { "" } else { " class=\"bad\"" },
        report.collisions.len(),
        plan.operations.iter().map(|o| o.moves.len()).sum::<usize>(),
        holders
    );
    if !by.is_empty() {
        h.push_str("<table>\n<tr><th>operation</th><th>tool part</th><th>against</th><th>moves</th><th>first move</th><th>deepest mm</th></tr>\n");
        for ((op, what, against), (n, pen, first)) in &by {
            let _ = writeln!(
                h,
                "<tr><td>{op}</td><td>{}</td><td>{}</td><td class=\"n\">{n}</td><td class=\"n\">{first}</td><td class=\"n\">{}</td></tr>",
                what.name(),
                escape(against),
                num(*pen, 3)
            );
        }
        h.push_str("</table>\n");
    }
    list(&mut h, "Not checked", &report.unchecked);
    let refusals: Vec<String> = plan
        .refusals
        .iter()
        .map(|r| {
            format!(
                "{} · {}: {}",
                format!("{:?}", r.stage).to_lowercase(),
                r.rule,
                r.reason
            )
        })
        .collect();
    list(&mut h, "Refusals", &refusals);
    list(&mut h, "Warnings", warnings);
    h.push_str("</body>\n</html>\n");
    h
}

fn list(h: &mut String, title: &str, items: &[String]) {
    let _ = writeln!(h, "<h3>{} ({})</h3>", escape(title), items.len());
    if items.is_empty() {
        return;
    }
    h.push_str("<ul class=\"warn\">\n");
    for i in items {
        let _ = writeln!(h, "<li>{}</li>", escape(i));
    }
    h.push_str("</ul>\n");
}

/// The box of the part's slabs in the set-up frame.
fn blank(part: &[Body]) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for b in part {
        lo = lo.min(b.lo.extend(b.z_lo));
        hi = hi.max(b.hi.extend(b.z_hi));
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    (lo, hi)
}

/// Top and bottom of a feature along up.
fn heights(f: &thinplan_plan::MachiningFeature, frame: &thinplan_brep::Frame) -> (f64, f64) {
    thinplan_collision::feature_body(f, frame)
        .map_or((f.shape.z_max, f.shape.z_min), |b| (b.z_hi, b.z_lo))
}

/// Area of a body's plan view (outer loops minus holes by orientation).
fn body_area(b: &Body) -> f64 {
    let signed: Vec<f64> = b.loops.iter().map(|l| shoelace(l)).collect();
    // The first loop is the outer one; holes subtract whatever their winding.
    let outer = signed.first().map_or(0.0, |a| a.abs());
    outer - signed.iter().skip(1).map(|a| a.abs()).sum::<f64>()
}

fn shoelace(l: &[DVec2]) -> f64 {
    let n = l.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (l[i], l[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
}

fn path_d(loops: &[Vec<DVec2>], map: &impl Fn(DVec2) -> DVec2) -> String {
    let mut d = String::new();
    for l in loops {
        for (i, p) in l.iter().enumerate() {
            let q = map(*p);
            let _ = write!(
                d,
                "{}{} {} ",
                if i == 0 { "M" } else { "L" },
                num(q.x, 2),
                num(q.y, 2)
            );
        }
        d.push_str("Z ");
    }
    d.trim_end().to_string()
}

/// Plan view along up: the blank, the part's sections (grey) and the
/// machining features coloured by owner, highest drawn last.
fn top_view(
    plan: &Plan,
    frame: &thinplan_brep::Frame,
    part: &[Body],
    lo: DVec3,
    hi: DVec3,
) -> String {
    let (w, h_max, m) = (720.0, 480.0, 30.0);
    let size = (hi - lo).truncate().max(DVec2::splat(1e-9));
    let scale = ((w - 2.0 * m) / size.x).min((h_max - 2.0 * m) / size.y);
    // As tall as the part needs.
    let hgt = (2.0 * m + size.y * scale).clamp(120.0, h_max).round();
    let map = |p: DVec2| DVec2::new(m + (p.x - lo.x) * scale, hgt - m - (p.y - lo.y) * scale);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{hgt}\" viewBox=\"0 0 {w} {hgt}\" role=\"img\" aria-label=\"top view of the part along up\">"
    );
    let a = map(lo.truncate());
    let b = map(hi.truncate());
    let _ = writeln!(
        s,
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\" stroke-dasharray=\"4 3\"/>",
        num(a.x, 2),
        num(b.y, 2),
        num(b.x - a.x, 2),
        num(a.y - b.y, 2)
    );
    // Part: every slab's section, faint, so overlaps show what is tall.
    for body in part {
        let _ = writeln!(
            s,
            "<path d=\"{}\" fill=\"#888\" fill-opacity=\"0.12\" fill-rule=\"evenodd\" stroke=\"#555\" stroke-width=\"0.6\"/>",
            path_d(&body.loops, &map)
        );
    }
    let mut feats: Vec<(f64, MachiningFeatureId, StiffnessFeatureId, Body)> = plan
        .machining_features
        .iter()
        .filter_map(|f| {
            thinplan_collision::feature_body(f, frame)
                .ok()
                .map(|b| (b.z_hi, f.id, f.owner, b))
        })
        .collect();
    feats.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    for (_, id, owner, body) in &feats {
        let _ = writeln!(
            s,
            "<path d=\"{}\" fill=\"{c}\" fill-opacity=\"0.25\" fill-rule=\"evenodd\" stroke=\"{c}\" stroke-width=\"1\"><title>{id} ({owner})</title></path>",
            path_d(&body.loops, &map),
            c = owner_colour(*owner)
        );
    }
    // Axes of the set-up frame.
    let o = DVec2::new(m * 0.4, hgt - m * 0.4);
    let _ = writeln!(
        s,
        "<g font-size=\"11\" fill=\"#333\"><path d=\"M{} {} h30 M{} {} v-30\" stroke=\"#333\"/><text x=\"{}\" y=\"{}\">x</text><text x=\"{}\" y=\"{}\">y</text></g>",
        num(o.x, 1),
        num(o.y, 1),
        num(o.x, 1),
        num(o.y, 1),
        num(o.x + 32.0, 1),
        num(o.y + 4.0, 1),
        num(o.x - 3.0, 1),
        num(o.y - 33.0, 1)
    );
    s.push_str("</svg>\n");
    // Legend by owner.
    let mut owners: Vec<StiffnessFeatureId> = feats.iter().map(|f| f.2).collect();
    owners.sort();
    owners.dedup();
    s.push_str("<p>");
    for o in owners {
        let _ = write!(
            s,
            "<span class=\"sw\" style=\"background:{}\"></span>{o} ",
            owner_colour(o)
        );
    }
    s.push_str(
        "— machining features by owner; grey: the part's sections; dashed: the blank.</p>\n",
    );
    s
}

/// Stage 9's verdict first: the one thing a planner must read before the
/// program runs.
fn verification(h: &mut String, plan: &Plan) {
    h.push_str("<h2>Verification</h2>\n");
    let Some(v) = &plan.verification else {
        h.push_str("<p><b>Not verified</b>: planning stopped before stage 9. Do not run a program made from this plan.</p>\n");
        return;
    };
    let _ = writeln!(
        h,
        "<p>Verdict: <b>{}</b> (the program replayed on a {} mm Z-map, {} replay(s)).</p>",
        escape(&v.verdict.name().to_uppercase()),
        v.cell_mm,
        v.rounds
    );
    if !v.left.is_empty() {
        h.push_str(
            "<table>\n<tr><th>material left</th><th>mm³</th><th>thickest mm</th><th>at</th></tr>\n",
        );
        for l in &v.left {
            let at =
                l.at.map_or(String::new(), |a| format!("({:.1}, {:.1})", a[0], a[1]));
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{:.2}</td><td>{:.2}</td><td>{}</td></tr>",
                escape(l.reason.name()),
                l.volume_mm3,
                l.worst_mm,
                at
            );
        }
        h.push_str("</table>\n");
    }
    if !v.removed.is_empty() || !v.problems.is_empty() {
        h.push_str("<table>\n<tr><th>operation</th><th>problem</th><th>at</th><th>depth mm</th><th></th></tr>\n");
        let rows = v
            .removed
            .iter()
            .map(|r| (&r.problem, "removed"))
            .chain(v.problems.iter().map(|p| (p, "in the program")));
        for (p, what) in rows {
            let op = p
                .operation
                .map_or_else(|| "-".to_string(), |o| o.to_string());
            let _ = writeln!(
                h,
                "<tr><td>{op}</td><td>{}</td><td>({:.2}, {:.2}, {:.2})</td><td>{:.3}</td><td>{what}</td></tr>",
                escape(p.kind.name()),
                p.at[0],
                p.at[1],
                p.at[2],
                p.depth_mm
            );
        }
        h.push_str("</table>\n");
    }
}
