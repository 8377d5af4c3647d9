//! SVG drawing of a pocket, the contours and the tool path (`thinplan pocket PROFILE --svg`).

use glam::DVec2;
use std::fmt::Write;

use crate::geom::sample_pline;
use crate::{Pocket, PocketPath};

fn poly(out: &mut String, pts: &[DVec2], closed: bool, style: &str) {
    if pts.is_empty() {
        return;
    }
    let tag = if closed { "polygon" } else { "polyline" };
    let _ = write!(out, "<{tag} fill=\"none\" {style} points=\"");
    for p in pts {
        let _ = write!(out, "{:.4},{:.4} ", p.x, p.y);
    }
    out.push_str("\"/>\n");
}

/// Draw the pocket wall (black), the tool-offset boundary (dashed grey), the PDE contours or
/// offset rings (thin blue), the roughing path (red), the finishing pass (green) and the
/// spiral centre. y points up.
pub fn pocket_svg(pocket: &Pocket, path: &PocketPath) -> String {
    let size = pocket.size().max(1e-9);
    let wall = sample_pline(&pocket.outer, size / 200.0, 2f64.to_radians());
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in wall.iter().chain(path.points.iter()) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let m = 0.05 * size;
    lo -= DVec2::splat(m);
    hi += DVec2::splat(m);
    let ext = hi - lo;
    let w = 0.002 * size;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"800\" height=\"{:.0}\" viewBox=\"{:.4} {:.4} {:.4} {:.4}\">",
        800.0 * ext.y / ext.x,
        lo.x,
        -hi.y,
        ext.x,
        ext.y
    );
    let _ = writeln!(
        out,
        "<title>{} — {} ({} points, max gap {:.3} mm)</title>",
        pocket.name,
        path.method.as_str(),
        path.points.len(),
        path.max_gap
    );
    out.push_str("<g transform=\"scale(1,-1)\">\n");
    poly(
        &mut out,
        &wall,
        true,
        &format!("stroke=\"black\" stroke-width=\"{:.4}\"", 2.0 * w),
    );
    for isl in &pocket.islands {
        let pts = sample_pline(isl, size / 200.0, 2f64.to_radians());
        poly(
            &mut out,
            &pts,
            true,
            &format!("stroke=\"black\" stroke-width=\"{:.4}\"", 2.0 * w),
        );
    }
    for c in &path.contours {
        poly(
            &mut out,
            c,
            true,
            &format!("stroke=\"#6fa8dc\" stroke-width=\"{:.4}\"", 0.5 * w),
        );
    }
    poly(
        &mut out,
        &path.boundary,
        true,
        &format!(
            "stroke=\"grey\" stroke-dasharray=\"{:.4}\" stroke-width=\"{:.4}\"",
            4.0 * w,
            w
        ),
    );
    let fs = path.finish_start.min(path.points.len());
    poly(
        &mut out,
        &path.points[..fs],
        false,
        &format!("stroke=\"#cc0000\" stroke-width=\"{:.4}\"", w),
    );
    if fs > 0 && fs < path.points.len() {
        poly(
            &mut out,
            &path.points[fs - 1..],
            false,
            &format!("stroke=\"#008800\" stroke-width=\"{:.4}\"", 1.5 * w),
        );
    }
    if let Some(c) = path.center {
        let _ = writeln!(
            out,
            "<circle cx=\"{:.4}\" cy=\"{:.4}\" r=\"{:.4}\" fill=\"#cc0000\"/>",
            c.x,
            c.y,
            4.0 * w
        );
    }
    out.push_str("</g>\n</svg>\n");
    out
}
