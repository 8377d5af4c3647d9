//! Points, directions, vectors and axis placements, scaled from the
//! file's length unit to millimetres.

use glam::DVec3;
use thinplan_brep::Frame;

use super::args::A;
use super::walk::Ctx;
use super::R;

impl<'x, 'a> Ctx<'x, 'a> {
    fn coords(&self, a: &A<'x, 'a>, i: usize) -> R<DVec3> {
        let l = a.list(i)?;
        if l.is_empty() || l.len() > 3 {
            return Err(a.wrong(format!("expected 1 to 3 coordinates, found {}", l.len())));
        }
        let mut c = [0.0; 3];
        for (k, v) in l.iter().enumerate() {
            c[k] = a.value_num(v, "coordinate")?;
        }
        Ok(DVec3::from_array(c))
    }

    pub(super) fn point(&mut self, idx: usize) -> R<DVec3> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["CARTESIAN_POINT"], "a point")?;
        Ok(self.coords(&a, 1)? * self.geo.scale)
    }

    fn direction(&mut self, idx: usize) -> R<DVec3> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["DIRECTION"], "a direction")?;
        self.coords(&a, 1)
    }

    /// Unit direction and length (scaled) of a `VECTOR`.
    pub(super) fn vector(&mut self, idx: usize) -> R<(DVec3, f64)> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["VECTOR"], "a vector")?;
        let d = self.direction(a.r(1)?)?;
        let m = a.num(2)? * self.geo.scale;
        Ok((d.try_normalize().unwrap_or(DVec3::Z), m))
    }

    pub(super) fn placement(&mut self, idx: usize) -> R<Frame> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["AXIS2_PLACEMENT_3D"], "a 3D placement")?;
        let origin = self.point(a.r(1)?)?;
        let axis = match a.opt_r(2)? {
            Some(i) => self.direction(i)?,
            None => DVec3::Z,
        };
        let refd = match a.opt_r(3)? {
            Some(i) => Some(self.direction(i)?),
            None => None,
        };
        Ok(Frame::from_axis_ref(origin, axis, refd))
    }

    pub(super) fn axis1(&mut self, idx: usize) -> R<(DVec3, DVec3)> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["AXIS1_PLACEMENT"], "an axis placement")?;
        let origin = self.point(a.r(1)?)?;
        let axis = match a.opt_r(2)? {
            Some(i) => self.direction(i)?,
            None => DVec3::Z,
        };
        Ok((origin, axis.try_normalize().unwrap_or(DVec3::Z)))
    }

    pub(super) fn length(&self, a: &A<'x, 'a>, i: usize) -> R<f64> {
        Ok(a.num(i)? * self.geo.scale)
    }
}
