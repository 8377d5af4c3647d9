//! 3D boundary segments (lines, arcs, full circles) and a point index.

use std::collections::HashMap;

use glam::DVec3;
use thinplan_brep::Frame;

/// A line, or an arc running counter-clockwise about `axis`. A full circle
/// has `a == b` (its seam point).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seg3 {
    pub a: DVec3,
    pub b: DVec3,
    pub arc: Option<Arc3>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arc3 {
    pub centre: DVec3,
    pub axis: DVec3,
    pub radius: f64,
    /// True for a full circle.
    pub full: bool,
}

/// The sign-normalised direction: first clearly non-zero component positive.
pub fn canon(v: DVec3) -> DVec3 {
    for c in [v.x, v.y, v.z] {
        if c.abs() > 1e-9 {
            return if c > 0.0 { v } else { -v };
        }
    }
    v
}

/// The seam point of a full circle: where its canonical frame's x axis meets it.
pub fn circle_seam(centre: DVec3, axis: DVec3, radius: f64) -> DVec3 {
    let f = Frame::from_axis_ref(centre, canon(axis), None);
    centre + f.x * radius
}

impl Arc3 {
    /// Local frame with x towards `start`, z = axis.
    fn basis(&self, start: DVec3) -> (DVec3, DVec3) {
        let x = (start - self.centre).normalize();
        (x, self.axis.cross(x))
    }
}

impl Seg3 {
    pub fn line(a: DVec3, b: DVec3) -> Seg3 {
        Seg3 { a, b, arc: None }
    }

    /// Sweep angle (0 for lines, 2π for full circles).
    pub fn sweep(&self) -> f64 {
        match self.arc {
            None => 0.0,
            Some(arc) if arc.full => std::f64::consts::TAU,
            Some(arc) => {
                let (x, y) = arc.basis(self.a);
                let d = self.b - arc.centre;
                let ang = d.dot(y).atan2(d.dot(x)).rem_euclid(std::f64::consts::TAU);
                if ang < 1e-12 {
                    std::f64::consts::TAU
                } else {
                    ang
                }
            }
        }
    }

    /// Point at parameter t ∈ [0, 1].
    pub fn point_at(&self, t: f64) -> DVec3 {
        match self.arc {
            None => self.a.lerp(self.b, t),
            Some(arc) => {
                let (x, y) = arc.basis(self.a);
                let ang = self.sweep() * t;
                arc.centre + (x * ang.cos() + y * ang.sin()) * arc.radius
            }
        }
    }

    pub fn midpoint(&self) -> DVec3 {
        self.point_at(0.5)
    }

    /// The parameter of `p` if it lies strictly inside the segment.
    pub fn interior_param(&self, p: DVec3, tol: f64) -> Option<f64> {
        match self.arc {
            None => {
                let d = self.b - self.a;
                let len = d.length();
                let t = (p - self.a).dot(d) / (len * len);
                if t * len <= tol || (1.0 - t) * len <= tol {
                    return None;
                }
                ((self.a + d * t).distance(p) <= tol).then_some(t)
            }
            Some(arc) => {
                let d = p - arc.centre;
                if d.dot(arc.axis).abs() > tol {
                    return None;
                }
                if (d.length() - arc.radius).abs() > tol {
                    return None;
                }
                let (x, y) = arc.basis(self.a);
                let ang = d.dot(y).atan2(d.dot(x)).rem_euclid(std::f64::consts::TAU);
                let sweep = self.sweep();
                let margin = tol / arc.radius;
                (ang > margin && ang < sweep - margin).then_some(ang / sweep)
            }
        }
    }

    /// Splits at increasing interior parameters, ending pieces at the given points.
    pub fn split(&self, cuts: &[(f64, DVec3)]) -> Vec<Seg3> {
        let mut out = Vec::with_capacity(cuts.len() + 1);
        let mut start = self.a;
        for &(_, p) in cuts {
            out.push(Seg3 {
                a: start,
                b: p,
                arc: self.arc.map(|a| Arc3 { full: false, ..a }),
            });
            start = p;
        }
        out.push(Seg3 {
            a: start,
            b: self.b,
            arc: self.arc.map(|a| Arc3 {
                full: a.full && cuts.is_empty(),
                ..a
            }),
        });
        out
    }

    /// Lower and upper corners of a box holding the segment.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match self.arc {
            None => (self.a.min(self.b), self.a.max(self.b)),
            Some(arc) => (
                arc.centre - DVec3::splat(arc.radius),
                arc.centre + DVec3::splat(arc.radius),
            ),
        }
    }

    pub fn reversed(&self) -> Seg3 {
        Seg3 {
            a: self.b,
            b: self.a,
            arc: self.arc.map(|a| Arc3 { axis: -a.axis, ..a }),
        }
    }
}

/// Points merged within a tolerance, on a hash grid.
pub struct PointIndex3 {
    pub pts: Vec<DVec3>,
    grid: HashMap<(i64, i64, i64), Vec<usize>>,
    cell: f64,
    tol: f64,
}

impl PointIndex3 {
    pub fn new(tol: f64) -> Self {
        PointIndex3 {
            pts: Vec::new(),
            grid: HashMap::new(),
            cell: tol * 4.0,
            tol,
        }
    }

    fn key(&self, p: DVec3) -> (i64, i64, i64) {
        let k = p / self.cell;
        (k.x.floor() as i64, k.y.floor() as i64, k.z.floor() as i64)
    }

    pub fn id(&mut self, p: DVec3) -> usize {
        let (kx, ky, kz) = self.key(p);
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.grid.get(&(kx + dx, ky + dy, kz + dz)) {
                        for &i in list {
                            let d = self.pts[i].distance(p);
                            if d <= self.tol && best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, i));
                            }
                        }
                    }
                }
            }
        }
        if let Some((_, i)) = best {
            return i;
        }
        self.pts.push(p);
        let i = self.pts.len() - 1;
        self.grid.entry((kx, ky, kz)).or_default().push(i);
        i
    }
}
