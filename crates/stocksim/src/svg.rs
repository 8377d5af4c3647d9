//! The top-view picture: one rectangle per run of equal colour in a grid
//! row, so the SVG stays small; self-contained (no scripts, no fonts beyond
//! the generic family).

use std::fmt::Write;

use crate::compare::CellClass;
use crate::Simulation;

const GOUGE: &str = "#d62728";
const MISSED: &str = "#ff7f0e";
const UNREACHABLE: &str = "#1f77b4";
const ABOVE_REACH: &str = "#9467bd";

/// The top view: gouges red, missed leftover orange, unreachable leftover
/// blue, leftover above what a tool reaches where none reaches the part
/// purple, good cells grey by part height (lighter = higher), through cells
/// (no part) white.
pub fn top_view(sim: &Simulation) -> String {
    let g = &sim.stock.grid;
    let (w_mm, h_mm) = (g.nx as f64 * g.cell, g.ny as f64 * g.cell);
    let scale = 800.0 / w_mm.max(h_mm).max(1e-9);
    let (w, h) = (w_mm * scale, h_mm * scale);
    let legend = 98.0;
    let zlo = sim.stock.blank.min.z as f32;
    let zhi = sim.stock.blank.max.z as f32;
    let colour = |k: usize| -> String {
        match sim.classes[k] {
            CellClass::Gouge => GOUGE.into(),
            CellClass::Missed => MISSED.into(),
            CellClass::Unreachable => UNREACHABLE.into(),
            CellClass::AboveReach => ABOVE_REACH.into(),
            CellClass::Ok => {
                let p = sim.part[k];
                if p <= zlo + 1e-4 {
                    "#ffffff".into()
                } else {
                    // Six grey levels keep the runs long.
                    let t = ((p - zlo) / (zhi - zlo).max(1e-6)).clamp(0.0, 1.0);
                    let level = (t * 5.0).round() as u32;
                    let v = 120 + level * 22;
                    format!("#{v:02x}{v:02x}{v:02x}")
                }
            }
        }
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" viewBox="0 0 {:.2} {:.2}" shape-rendering="crispEdges">"#,
        w + 20.0,
        h + legend + 20.0,
        w + 20.0,
        h + legend + 20.0
    );
    let _ = writeln!(s, "<title>thinplan stock simulation, top view</title>");
    let _ = writeln!(
        s,
        r##"<rect x="10" y="10" width="{w:.2}" height="{h:.2}" fill="#ffffff" stroke="#000000" stroke-width="0.5"/>"##
    );
    let cs = g.cell * scale;
    for j in 0..g.ny {
        let y = 10.0 + h - (j + 1) as f64 * cs;
        let mut i = 0;
        while i < g.nx {
            let c = colour(j * g.nx + i);
            let mut e = i + 1;
            while e < g.nx && colour(j * g.nx + e) == c {
                e += 1;
            }
            if c != "#ffffff" {
                let _ = writeln!(
                    s,
                    r#"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="{c}"/>"#,
                    10.0 + i as f64 * cs,
                    y,
                    (e - i) as f64 * cs,
                    cs
                );
            }
            i = e;
        }
    }
    let r = &sim.report;
    let ly = h + 30.0;
    let items = [
        (
            GOUGE,
            format!(
                "gouge: {} cells, worst {:.3} mm",
                r.gouges.cells, r.gouges.worst_mm
            ),
        ),
        (
            MISSED,
            format!(
                "missed: {} cells, {:.1} mm³",
                r.leftover_missed.cells, r.leftover_missed.volume_mm3
            ),
        ),
        (
            UNREACHABLE,
            format!(
                "unreachable: {} cells, {:.1} mm³",
                r.leftover_unreachable.cells, r.leftover_unreachable.volume_mm3
            ),
        ),
        (
            ABOVE_REACH,
            format!(
                "above reach: {} cells, {:.2} mm³",
                r.leftover_above_reach.cells, r.leftover_above_reach.volume_mm3
            ),
        ),
    ];
    // Two rows of two: the counts make the texts long.
    for (k, (col, text)) in items.iter().enumerate() {
        let x = 10.0 + (k % 2) as f64 * (w / 2.0).max(300.0);
        let y = ly + (k / 2) as f64 * 18.0;
        let _ = writeln!(
            s,
            r#"<rect x="{x:.1}" y="{y:.1}" width="12" height="12" fill="{col}"/>"#
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" font-family="sans-serif" font-size="12">{}</text>"#,
            x + 16.0,
            y + 11.0,
            text
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="10" y="{:.1}" font-family="sans-serif" font-size="12">cell {} mm, tol {} mm, feed {:.0} mm, rapid {:.0} mm, air {:.1} %, removed {:.0} mm³</text>"#,
        ly + 48.0,
        r.cell_mm,
        r.tolerance_mm,
        r.program.feed_length_mm,
        r.program.rapid_length_mm,
        r.air_cutting.share * 100.0,
        r.removed_volume_mm3
    );
    let _ = writeln!(
        s,
        r#"<text x="10" y="{:.1}" font-family="sans-serif" font-size="12">grey: within tolerance (lighter = higher part); white: through (no part)</text>"#,
        ly + 66.0
    );
    s.push_str("</svg>\n");
    s
}
