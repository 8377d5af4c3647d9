//! A section across a wall (horizontal: offset from the wall's mid-plane
//! along its normal made horizontal; vertical: height along up), shared by
//! the pictures of one wall: its machining features in order (figure 4.1)
//! and its operation layers (figure 7.9).

use std::fmt::Write as _;

use glam::{DVec2, DVec3};
use thinplan_brep::Frame;
use thinplan_plan::{MachiningFeature, Plan, StiffnessFeature, StiffnessFeatureId};

use crate::{escape, num};

pub(crate) struct Section<'p> {
    pub sf: Option<&'p StiffnessFeature>,
    /// The section plane's horizontal axis (the wall's normal) and up.
    pub n: DVec3,
    pub up: DVec3,
    /// Along the wall, towards the viewer.
    pub w: DVec3,
    /// The wall's mid-plane offset along `n`, subtracted by [`Section::at`].
    pub centre: f64,
    /// The wall's box in the section.
    pub wall: Option<(DVec2, DVec2)>,
    /// The wall's machining features with their boxes in the section, by id.
    pub features: Vec<(&'p MachiningFeature, DVec2, DVec2)>,
}

impl<'p> Section<'p> {
    pub fn of(plan: &'p Plan, owner: StiffnessFeatureId) -> Section<'p> {
        let up = plan.setup.up.normalize_or_zero();
        let sf = plan.stiffness_features.iter().find(|s| s.id == owner);
        let setup = thinplan_collision::setup_frame(plan.setup.up);
        let normal = sf.map_or(setup.x, |s| s.axis);
        let n = (normal - up * normal.dot(up))
            .try_normalize()
            .unwrap_or(setup.x);
        let w = up.cross(n);
        let mut section = Section {
            sf,
            n,
            up,
            w,
            centre: 0.0,
            wall: None,
            features: Vec::new(),
        };
        if let Some(shape) = sf.and_then(|s| s.shape.as_ref()) {
            let f = Frame::from_axis_ref(shape.frame.origin, shape.frame.z, Some(shape.frame.x));
            let pts = shape.region.outer.vertices.iter().flat_map(|v| {
                [shape.z_min, shape.z_max].map(|z| f.to_world(DVec3::new(v.x, v.y, z)))
            });
            if let Some((lo, hi)) = section.bounds(pts) {
                section.centre = 0.5 * (lo.x + hi.x);
                let c = DVec2::new(section.centre, 0.0);
                section.wall = Some((lo - c, hi - c));
            }
        }
        for f in plan.machining_features.iter().filter(|f| f.owner == owner) {
            let fr =
                Frame::from_axis_ref(f.shape.frame.origin, f.shape.frame.z, Some(f.shape.frame.x));
            let pts = thinplan_collision::loop_points(&f.shape.region.outer)
                .into_iter()
                .flat_map(|p| {
                    [f.shape.z_min, f.shape.z_max].map(|z| fr.to_world(DVec3::new(p.x, p.y, z)))
                });
            if let Some((lo, hi)) = section.bounds(pts) {
                section.features.push((f, lo, hi));
            }
        }
        section
    }

    /// A picture's title: the wall and its role, then `what`.
    pub fn title(&self, owner: StiffnessFeatureId, what: &str) -> String {
        match self.sf {
            Some(f) => {
                let role = f
                    .role
                    .map_or(String::new(), |r| format!(" {r:?}").to_lowercase());
                format!("{}{role}: {what}", f.id)
            }
            None => format!("{owner}: no such stiffness feature"),
        }
    }

    /// A point in the section.
    pub fn at(&self, p: DVec3) -> DVec2 {
        DVec2::new(p.dot(self.n) - self.centre, p.dot(self.up))
    }

    fn bounds(&self, pts: impl Iterator<Item = DVec3>) -> Option<(DVec2, DVec2)> {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for p in pts {
            let q = self.at(p);
            lo = lo.min(q);
            hi = hi.max(q);
        }
        (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
    }
}

/// The section's box `lo`–`hi` fitted into a picture `w_max` wide at most
/// and `h_px` tall inside the margins (left, right, top, bottom): as wide as
/// the section needs, but room for the title. An empty box becomes
/// 20 × 10 mm.
pub(crate) struct Canvas {
    pub lo: DVec2,
    pub hi: DVec2,
    pub w_px: f64,
    pub h_px: f64,
    pub ml: f64,
    pub mr: f64,
    pub mt: f64,
    pub mb: f64,
    /// Pixels per mm.
    pub scale: f64,
}

impl Canvas {
    pub fn fit(
        mut lo: DVec2,
        mut hi: DVec2,
        (ml, mr, mt, mb): (f64, f64, f64, f64),
        w_max: f64,
        h_px: f64,
    ) -> Canvas {
        if !(lo.is_finite() && hi.is_finite()) {
            lo = DVec2::new(-10.0, 0.0);
            hi = DVec2::new(10.0, 10.0);
        }
        let size = (hi - lo).max(DVec2::splat(1e-6));
        let scale = ((w_max - ml - mr) / size.x).min((h_px - mt - mb) / size.y);
        let w_px = (ml + mr + size.x * scale).clamp(820.0, w_max).round();
        Canvas {
            lo,
            hi,
            w_px,
            h_px,
            ml,
            mr,
            mt,
            mb,
            scale,
        }
    }

    /// A section point in pixels.
    pub fn map(&self, p: DVec2) -> DVec2 {
        DVec2::new(
            self.ml + (p.x - self.lo.x) * self.scale,
            self.h_px - self.mb - (p.y - self.lo.y) * self.scale,
        )
    }
}

/// The picture's frame: the `<svg>` element on white, the title, the axes'
/// meaning (the section's horizontal direction `n`), and height ticks every
/// 10 mm (1 mm for small pictures) over the canvas's box.
pub(crate) fn frame(s: &mut String, c: &Canvas, title: &str, n: DVec3) {
    let (w_px, h_px, ml, mr, lo, hi) = (c.w_px, c.h_px, c.ml, c.mr, c.lo, c.hi);
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w_px}\" height=\"{h_px}\" viewBox=\"0 0 {w_px} {h_px}\" font-family=\"sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(
        s,
        "<rect width=\"{w_px}\" height=\"{h_px}\" fill=\"white\"/>"
    );
    let _ = writeln!(
        s,
        "<text x=\"{ml}\" y=\"22\" font-size=\"15\">{}</text>",
        escape(title)
    );
    let _ = writeln!(
        s,
        "<text x=\"{ml}\" y=\"38\" fill=\"#555\">horizontal: offset from the wall's mid-plane along {}, mm; vertical: height along up, mm</text>",
        escape(&format!("({}, {}, {})", num(n.x, 3), num(n.y, 3), num(n.z, 3)))
    );
    let step = if hi.y - lo.y > 30.0 { 10.0 } else { 1.0 };
    let mut z = (lo.y / step).ceil() * step;
    while z <= hi.y + 1e-9 {
        let p = c.map(DVec2::new(lo.x, z));
        let _ = writeln!(
            s,
            "<path d=\"M{} {} H{}\" stroke=\"#eee\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\" fill=\"#555\">{}</text>",
            num(ml - 4.0, 1),
            num(p.y, 2),
            num(w_px - mr, 1),
            num(ml - 8.0, 1),
            num(p.y + 4.0, 2),
            num(z, 0)
        );
        z += step;
    }
}
