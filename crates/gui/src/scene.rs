//! The 3D scene on the CPU side: the part's triangles, the feature prisms
//! as closed triangle meshes, the tool paths as line segments, one object
//! index per selectable thing, and picking by ray. Built once per plan
//! change; the GPU copy is uploaded from it once (see `render.rs`).

use std::ops::Range;

use glam::{DVec2, DVec3, Mat4, Vec3, Vec4};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
use thinplan_plan::{Plan, Prism, ProfileLoop, Region3};

use crate::state::Entity;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshVertex {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    pub object: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LineVertex {
    pub pos: [f32; 3],
    /// RGBA8, the tool-path region's colour.
    pub color: [u8; 4],
    pub object: u32,
}

/// Everything the viewport draws, with the object table.
#[derive(Default)]
pub struct Scene {
    /// Changes whenever the geometry does (the GPU copy follows it).
    pub generation: u64,
    /// Object index → what it shows; 0 is the part.
    pub objects: Vec<Entity>,
    pub vertices: Vec<MeshVertex>,
    pub indices: Vec<u32>,
    /// Index ranges: the part, then the features.
    pub part_indices: Range<u32>,
    pub feature_indices: Range<u32>,
    pub lines: Vec<LineVertex>,
    /// Per object: its index range and box, for picking.
    pub pick: Vec<(Range<u32>, Vec3, Vec3)>,
    pub min: Vec3,
    pub max: Vec3,
    /// Faces the tessellator could not do (shown as a warning).
    pub failed_faces: usize,
}

pub fn region_color(r: Region3) -> [u8; 4] {
    match r {
        Region3::Boundary => [255, 150, 40, 255],
        Region3::FullCut => [230, 60, 60, 255],
        Region3::Rest => [80, 200, 90, 255],
        Region3::Rapid => [150, 150, 150, 255],
        Region3::Link => [80, 150, 255, 255],
    }
}

impl Scene {
    /// Builds the scene of a plan and its part's B-rep.
    pub fn build(plan: &Plan, brep: Option<&thinplan_brep::Brep>, generation: u64) -> Scene {
        let mut s = Scene {
            generation,
            min: Vec3::splat(f32::INFINITY),
            max: Vec3::splat(f32::NEG_INFINITY),
            ..Default::default()
        };
        s.objects.push(Entity::Part);
        let start = s.indices.len() as u32;
        if let Some(brep) = brep {
            let b = plan.part.summary.bbox;
            let diag = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            let mesh = thinplan_brep::tessellate(
                brep,
                &thinplan_brep::TessTolerance::relative(diag, 0.002),
            );
            s.failed_faces = mesh.failed_faces.len();
            let base = s.vertices.len() as u32;
            for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
                s.push_vertex(*p, *n, 0);
            }
            for t in &mesh.triangles {
                s.indices.extend(t.iter().map(|i| base + i));
            }
        }
        let end = s.indices.len() as u32;
        s.part_indices = start..end;
        s.pick.push((start..end, s.min, s.max));
        for f in &plan.stiffness_features {
            if let Some(shape) = &f.shape {
                s.add_prism(Entity::Stiffness(f.id), shape);
            }
        }
        for f in &plan.machining_features {
            s.add_prism(Entity::Machining(f.id), &f.shape);
        }
        s.feature_indices = end..s.indices.len() as u32;
        for op in &plan.operations {
            let obj = s.objects.len() as u32;
            s.objects.push(Entity::Operation(op.id));
            let (lo, hi) = (s.min, s.max);
            let mut prev = op.start;
            for m in &op.moves {
                let col = region_color(m.region);
                match &m.arc {
                    Some(a) => {
                        let pts = arc_points(prev, m.to, a.centre, a.axis, a.clockwise);
                        let mut q = prev;
                        for p in pts {
                            s.push_line(q, p, col, obj);
                            q = p;
                        }
                    }
                    None => s.push_line(prev, m.to, col, obj),
                }
                prev = m.to;
            }
            // Operations are picked through their feature, not by lines.
            s.pick.push((0..0, lo, hi));
        }
        if s.min.x > s.max.x {
            s.min = Vec3::splat(-1.0);
            s.max = Vec3::splat(1.0);
        }
        s
    }

    fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn push_vertex(&mut self, p: DVec3, n: DVec3, object: u32) {
        let p = p.as_vec3();
        self.grow(p);
        self.vertices.push(MeshVertex {
            pos: p.to_array(),
            normal: n.as_vec3().to_array(),
            object,
        });
    }

    fn push_line(&mut self, a: DVec3, b: DVec3, color: [u8; 4], object: u32) {
        for p in [a, b] {
            let p = p.as_vec3();
            self.grow(p);
            self.lines.push(LineVertex {
                pos: p.to_array(),
                color,
                object,
            });
        }
    }

    /// Adds a prism as a closed mesh: two caps and the side quads.
    pub fn add_prism(&mut self, e: Entity, prism: &Prism) {
        let obj = self.objects.len() as u32;
        self.objects.push(e);
        let start = self.indices.len() as u32;
        let (lo0, hi0) = (self.min, self.max);
        self.min = Vec3::splat(f32::INFINITY);
        self.max = Vec3::splat(f32::NEG_INFINITY);
        let f = &prism.frame;
        let (x, z) = (f.x.normalize_or_zero(), f.z.normalize_or_zero());
        let y = z.cross(x);
        let o = f.origin;
        let at = |p: DVec2, w: f64| o + x * p.x + y * p.y + z * w;
        let loops: Vec<Vec<DVec2>> = std::iter::once(&prism.region.outer)
            .chain(&prism.region.holes)
            .map(loop_points)
            .filter(|l| l.len() >= 3)
            .collect();
        // Sides.
        for l in &loops {
            for i in 0..l.len() {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                let d = b - a;
                let n2 = DVec2::new(d.y, -d.x).normalize_or_zero();
                let n = x * n2.x + y * n2.y;
                let base = self.vertices.len() as u32;
                for (p, w) in [
                    (a, prism.z_min),
                    (b, prism.z_min),
                    (b, prism.z_max),
                    (a, prism.z_max),
                ] {
                    self.push_vertex(at(p, w), n, obj);
                }
                self.indices
                    .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        // Caps.
        for tri in triangulate(&loops) {
            for (w, n, flip) in [(prism.z_max, z, false), (prism.z_min, -z, true)] {
                let base = self.vertices.len() as u32;
                for p in tri {
                    self.push_vertex(at(p, w), n, obj);
                }
                if flip {
                    self.indices.extend([base, base + 2, base + 1]);
                } else {
                    self.indices.extend([base, base + 1, base + 2]);
                }
            }
        }
        let end = self.indices.len() as u32;
        let (mn, mx) = (self.min, self.max);
        self.pick.push((start..end, mn, mx));
        self.min = lo0.min(mn);
        self.max = hi0.max(mx);
    }

    /// The nearest object hit by a ray among the features (then the part),
    /// with its distance.
    pub fn pick(&self, origin: Vec3, dir: Vec3, visible: impl Fn(usize) -> bool) -> Option<usize> {
        let mut best: Option<(f32, usize)> = None;
        let mut part_hit: Option<(f32, usize)> = None;
        for (obj, (range, mn, mx)) in self.pick.iter().enumerate() {
            if range.is_empty() || !visible(obj) || !ray_box(origin, dir, *mn, *mx) {
                continue;
            }
            for t in self.indices[range.start as usize..range.end as usize].chunks_exact(3) {
                let p = |i: u32| Vec3::from(self.vertices[i as usize].pos);
                if let Some(d) = ray_triangle(origin, dir, p(t[0]), p(t[1]), p(t[2])) {
                    let slot = if obj == 0 { &mut part_hit } else { &mut best };
                    if slot.is_none_or(|(bd, _)| d < bd) {
                        *slot = Some((d, obj));
                    }
                }
            }
        }
        best.or(part_hit).map(|(_, o)| o)
    }
}

/// A loop's points with bulge arcs divided into short chords.
pub fn loop_points(l: &ProfileLoop) -> Vec<DVec2> {
    let v = &l.vertices;
    let mut out = Vec::new();
    for i in 0..v.len() {
        let a = DVec2::new(v[i].x, v[i].y);
        let b = DVec2::new(v[(i + 1) % v.len()].x, v[(i + 1) % v.len()].y);
        if !(a.is_finite() && b.is_finite()) {
            continue;
        }
        out.push(a);
        let bulge = v[i].bulge;
        if bulge.abs() > 1e-9 && bulge.is_finite() && (b - a).length() > 1e-12 {
            let theta = 4.0 * bulge.atan();
            let d = b - a;
            let c = d.length();
            let n = DVec2::new(-d.y, d.x) / c;
            let centre = (a + b) * 0.5 + n * (c * 0.5 / (theta * 0.5).tan());
            let r = (a - centre).length();
            let a0 = (a - centre).y.atan2((a - centre).x);
            let steps =
                ((theta.abs() / (std::f64::consts::PI / 16.0)).ceil() as usize).clamp(1, 64);
            for k in 1..steps {
                let t = a0 + theta * k as f64 / steps as f64;
                out.push(centre + DVec2::new(t.cos(), t.sin()) * r);
            }
        }
    }
    out.dedup_by(|p, q| (*p - *q).length() < 1e-9);
    out
}

/// Triangles of a region given as loops (outer first), by constrained
/// Delaunay triangulation keeping the triangles inside by even-odd.
pub fn triangulate(loops: &[Vec<DVec2>]) -> Vec<[DVec2; 3]> {
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    for l in loops {
        let handles: Vec<_> = l
            .iter()
            .filter_map(|p| cdt.insert(Point2::new(p.x, p.y)).ok())
            .collect();
        for i in 0..handles.len() {
            let (a, b) = (handles[i], handles[(i + 1) % handles.len()]);
            if a != b && cdt.can_add_constraint(a, b) {
                cdt.add_constraint(a, b);
            }
        }
    }
    let inside = |p: DVec2| {
        let mut c = false;
        for l in loops {
            for i in 0..l.len() {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x)
                {
                    c = !c;
                }
            }
        }
        c
    };
    cdt.inner_faces()
        .filter_map(|f| {
            let v = f.vertices().map(|v| {
                let p = v.position();
                DVec2::new(p.x, p.y)
            });
            let centroid = (v[0] + v[1] + v[2]) / 3.0;
            inside(centroid).then_some(v)
        })
        .collect()
}

/// Points along an arc about `centre` (plane normal to `axis`) from `a` to
/// `b`, `b` included.
pub fn arc_points(a: DVec3, b: DVec3, centre: DVec3, axis: DVec3, clockwise: bool) -> Vec<DVec3> {
    let z = axis.normalize_or_zero();
    let ra = a - centre;
    let ra_in = ra - z * ra.dot(z);
    let r = ra_in.length();
    if z == DVec3::ZERO || r < 1e-12 {
        return vec![b];
    }
    let ex = ra_in / r;
    let ey = z.cross(ex);
    let rb = b - centre;
    let mut sweep = rb.dot(ey).atan2(rb.dot(ex));
    if clockwise {
        if sweep >= -1e-12 {
            sweep -= std::f64::consts::TAU;
        }
    } else if sweep <= 1e-12 {
        sweep += std::f64::consts::TAU;
    }
    let steps = ((sweep.abs() / (std::f64::consts::PI / 24.0)).ceil() as usize).clamp(1, 96);
    let (ha, hb) = (ra.dot(z), rb.dot(z));
    (1..=steps)
        .map(|k| {
            let t = k as f64 / steps as f64;
            if k == steps {
                return b;
            }
            let ang = sweep * t;
            centre + (ex * ang.cos() + ey * ang.sin()) * r + z * (ha + (hb - ha) * t)
        })
        .collect()
}

fn ray_box(o: Vec3, d: Vec3, mn: Vec3, mx: Vec3) -> bool {
    let inv = d.recip();
    let t1 = (mn - o) * inv;
    let t2 = (mx - o) * inv;
    let tmin = t1.min(t2).max_element();
    let tmax = t1.max(t2).min_element();
    tmax >= tmin.max(0.0)
}

fn ray_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// An orbiting camera around a target, z up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub target: Vec3,
    pub distance: f32,
    /// Radians about z.
    pub yaw: f32,
    /// Radians above the xy plane.
    pub pitch: f32,
    pub fov_y: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            target: Vec3::ZERO,
            distance: 100.0,
            yaw: -0.9,
            pitch: 0.55,
            fov_y: 0.7,
        }
    }
}

impl Camera {
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + Vec3::new(cp * cy, cp * sy, sp) * self.distance
    }

    pub fn fit(&mut self, min: Vec3, max: Vec3) {
        self.target = (min + max) * 0.5;
        let r = ((max - min).length() * 0.5).max(1e-3);
        self.distance = r / (self.fov_y * 0.5).sin() * 1.05;
    }

    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.01;
        self.pitch = (self.pitch + dy * 0.01).clamp(-1.55, 1.55);
    }

    pub fn pan(&mut self, dx: f32, dy: f32, height_px: f32) {
        let eye = self.eye();
        let fwd = (self.target - eye).normalize_or_zero();
        let right = fwd.cross(Vec3::Z).normalize_or(Vec3::X);
        let up = right.cross(fwd);
        let scale = 2.0 * self.distance * (self.fov_y * 0.5).tan() / height_px.max(1.0);
        self.target += (-right * dx + up * dy) * scale;
    }

    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance * factor).clamp(1e-3, 1e7);
    }

    pub fn view(&self) -> Mat4 {
        let eye = self.eye();
        let f = (self.target - eye).normalize_or(Vec3::NEG_Z);
        let s = f.cross(Vec3::Z).normalize_or(Vec3::X);
        let u = s.cross(f);
        Mat4::from_cols(
            Vec4::new(s.x, u.x, -f.x, 0.0),
            Vec4::new(s.y, u.y, -f.y, 0.0),
            Vec4::new(s.z, u.z, -f.z, 0.0),
            Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        )
    }

    /// Right-handed perspective with depth 0..1 (as wgpu wants).
    pub fn proj(&self, aspect: f32) -> Mat4 {
        let near = (self.distance * 0.01).max(1e-4);
        let far = self.distance * 100.0;
        let h = 1.0 / (self.fov_y * 0.5).tan();
        let w = h / aspect.max(1e-6);
        let r = far / (near - far);
        Mat4::from_cols(
            Vec4::new(w, 0.0, 0.0, 0.0),
            Vec4::new(0.0, h, 0.0, 0.0),
            Vec4::new(0.0, 0.0, r, -1.0),
            Vec4::new(0.0, 0.0, r * near, 0.0),
        )
    }

    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.proj(aspect) * self.view()
    }

    /// The ray through a point of the viewport given in -1..1 (y up).
    pub fn ray(&self, ndc_x: f32, ndc_y: f32, aspect: f32) -> (Vec3, Vec3) {
        let inv = self.view_proj(aspect).inverse();
        let a = inv.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
        let b = inv.project_point3(Vec3::new(ndc_x, ndc_y, 0.5));
        (a, (b - a).normalize_or(Vec3::NEG_Z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::{PrismFrame, ProfileVertex, Region};

    fn square(s: f64, cw: bool) -> ProfileLoop {
        let mut v: Vec<ProfileVertex> = [(-s, -s), (s, -s), (s, s), (-s, s)]
            .iter()
            .map(|&(x, y)| ProfileVertex { x, y, bulge: 0.0 })
            .collect();
        if cw {
            v.reverse();
        }
        ProfileLoop { vertices: v }
    }

    #[test]
    fn a_square_with_a_hole_has_the_right_cap_area() {
        let loops = vec![
            loop_points(&square(2.0, false)),
            loop_points(&square(1.0, true)),
        ];
        let area: f64 = triangulate(&loops)
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs())
            .sum();
        assert!((area - 12.0).abs() < 1e-9, "{area}");
    }

    #[test]
    fn a_bulge_of_one_is_a_half_circle() {
        let l = ProfileLoop {
            vertices: vec![
                ProfileVertex {
                    x: -1.0,
                    y: 0.0,
                    bulge: 1.0,
                },
                ProfileVertex {
                    x: 1.0,
                    y: 0.0,
                    bulge: 1.0,
                },
            ],
        };
        let pts = loop_points(&l);
        assert!(pts.len() > 10);
        for p in &pts {
            assert!((p.length() - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn picking_finds_the_prism_in_front() {
        let mut s = Scene::default();
        s.objects.push(Entity::Part);
        s.pick.push((0..0, Vec3::ZERO, Vec3::ZERO));
        let prism = |z0: f64| Prism {
            frame: PrismFrame {
                origin: DVec3::ZERO,
                x: DVec3::X,
                z: DVec3::Z,
            },
            region: Region {
                outer: square(1.0, false),
                holes: vec![],
            },
            z_min: z0,
            z_max: z0 + 1.0,
        };
        let a = thinplan_plan::MachiningFeatureId(0);
        let b = thinplan_plan::MachiningFeatureId(1);
        s.add_prism(Entity::Machining(a), &prism(0.0));
        s.add_prism(Entity::Machining(b), &prism(5.0));
        let hit = s.pick(Vec3::new(0.1, 0.2, 20.0), Vec3::NEG_Z, |_| true);
        assert_eq!(hit.map(|o| s.objects[o]), Some(Entity::Machining(b)));
        let hit = s.pick(Vec3::new(0.1, 0.2, 20.0), Vec3::NEG_Z, |o| o != 2);
        assert_eq!(hit.map(|o| s.objects[o]), Some(Entity::Machining(a)));
    }

    #[test]
    fn camera_ray_goes_through_the_target() {
        let mut c = Camera::default();
        c.fit(Vec3::splat(-1.0), Vec3::splat(1.0));
        let (o, d) = c.ray(0.0, 0.0, 1.5);
        let to_t = (c.target - o).normalize();
        assert!(to_t.dot(d) > 0.9999);
        let clip = c.view_proj(1.5) * c.target.extend(1.0);
        let z = clip.z / clip.w;
        assert!((0.0..=1.0).contains(&z));
    }
}
