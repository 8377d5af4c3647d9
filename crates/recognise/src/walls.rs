//! Walls: pairs of opposite faces a small distance apart (thesis §5.4.1,
//! §6.1.1), free-shaped.
//!
//! # Algorithm
//!
//! 1. **Planar pairs.** Planar faces are bucketed by their (sign-normalised)
//!    normal direction and sorted by plane offset along it. A face `a` whose
//!    outward normal is `+c` is paired with the faces `b` whose outward normal
//!    is `−c` lying behind it (offset `s_b` in `[s_a − t_max, s_a)`): the
//!    material is between them. Candidates are filtered by their 2D boxes in
//!    the bucket's plane frame, then their tessellations (triangles in that
//!    frame) are clipped against each other: the pair counts only when the
//!    projected regions share area (not just boxes). A pair is refused when
//!    a parallel face lies between the two planes over the shared area (a
//!    cavity: no material between them). Binary search on the sorted offsets
//!    keeps this near-linear (no pair scan over all faces).
//! 2. **Coaxial cylinders** (curved walls): a convex cylinder and a concave
//!    one on the same axis, radii `R > r`, `t = R − r`, sharing an angular and
//!    axial range (clipped in the unrolled `(r_mid·θ, axial)` plane).
//! 3. **Merging.** Pairs on the same two planes are grouped into connected
//!    components (faces linked by pairs). Components on the same two planes
//!    that are separated by a crossing wall — one touches one side plane of
//!    another wall, the other touches that wall's opposite side plane, and
//!    they lie on either side of its slab — are merged, so crossing walls
//!    stay whole (§6.1.1, "coplanar faces are considered part of the same
//!    wall").
//! 4. **Attributes.** Thickness `t`; for a web (normal along `up`) the length
//!    and height are the larger and smaller in-plane extents of the shared
//!    region; for other walls height is the extent along the in-plane
//!    projection of `up` and length the extent along `normal × up`.
//! 5. **Thinness** (knowledge): `t ≤ max_thickness` and
//!    `height / t ≥ min_height_to_thickness`. A web candidate that is not thin
//!    but at most `max_base_thickness` thick is kept when a thin wall touches
//!    it (rule `recognise.wall.support_base`): it is the base the thin walls
//!    stand on.
//! 6. **Role** (set-up frame): `web` when the normal is along `up`. Another
//!    wall touching a web is a `flange` when that web does not continue past
//!    the wall (the web's shared region ends at the wall's slab: the wall is
//!    at the web's boundary), and a `rib` when the web continues on both
//!    sides of it or when it touches no web (e.g. a rib on a flange).
//!
//! A wall's `faces` are its side faces (both sides); end faces (a rib's top,
//! cut-out flanks) are left to the depression recogniser. `axis` is the
//! wall normal with its first non-zero component positive. `shape` is the
//! mid-surface as a [`Prism`]: for planar walls the frame's z is the wall
//! normal, the origin on the mid-plane, x along the length, the region the
//! side outline (the exact loops, lines and arcs, of the smaller side when it
//! is one face, else the shared region's bounding rectangle), z in
//! `[−t/2, t/2]`; for curved walls the frame's z is the cylinder axis and
//! the region the annular sector (two arcs, two lines) over the axial range.

use std::collections::{BTreeMap, BTreeSet};

use glam::{DVec2, DVec3};
use thinplan_brep::{Brep, EdgeAdjacency, FaceId, Frame, Surface, TessTolerance};
use thinplan_knowledge::WallRecognition;
use thinplan_plan::{
    Prism, PrismFrame, ProfileLoop, ProfileVertex, Provenance, ProvenanceSource, Region,
    StiffnessFeature, StiffnessFeatureId, StiffnessKind, WallRole,
};

/// Rule ids recorded in provenance.
pub const RULE_PLANES: &str = "recognise.wall.opposite_planes";
pub const RULE_CYLINDERS: &str = "recognise.wall.coaxial_cylinders";
pub const RULE_SUPPORT: &str = "recognise.wall.support_base";

/// A 2D polygon (convex piece of a shared region).
type Poly = Vec<DVec2>;

/// One planar face, as seen from its direction bucket.
#[derive(Debug, Clone)]
struct PlaneFace {
    face: FaceId,
    /// Offset along the bucket direction.
    s: f64,
    /// Outward normal along `+c` (true) or `−c`.
    plus: bool,
}

/// Triangles of a face in some 2D frame, with their box.
#[derive(Debug, Clone, Default)]
struct Tris {
    tris: Vec<[DVec2; 3]>,
    min: DVec2,
    max: DVec2,
}

impl Tris {
    fn overlaps_box(&self, o: &Tris, tol: f64) -> bool {
        self.min.x <= o.max.x + tol
            && o.min.x <= self.max.x + tol
            && self.min.y <= o.max.y + tol
            && o.min.y <= self.max.y + tol
    }

    fn contains(&self, p: DVec2) -> bool {
        if p.x < self.min.x || p.y < self.min.y || p.x > self.max.x || p.y > self.max.y {
            return false;
        }
        self.tris.iter().any(|t| point_in_tri(p, t))
    }
}

/// What kind of surface pair a wall comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum PairKind {
    /// Direction bucket index and the two plane offsets (`s_plus > s_minus`).
    Planes,
    /// Cylinder axis frame and radii (outer, inner).
    Cylinders {
        frame: Frame,
        outer: f64,
        inner: f64,
    },
}

/// A found pair of opposite faces.
#[derive(Debug, Clone)]
struct Pair {
    /// Face on the `+c` side (planes) or the outer cylinder.
    a: FaceId,
    /// Face on the `−c` side or the inner cylinder.
    b: FaceId,
    /// Grouping key: which two surfaces.
    key: usize,
    /// Shared region pieces in the key's 2D frame.
    pieces: Vec<Poly>,
}

/// A group key: two planes (or two cylinders) and the frame for 2D work.
#[derive(Debug, Clone)]
struct Key {
    kind: PairKind,
    /// Wall normal (canonical sign); for cylinders the normal at mid-angle is
    /// filled in later.
    c: DVec3,
    frame: Frame,
    s_plus: f64,
    s_minus: f64,
}

/// A wall under construction.
#[derive(Debug, Clone)]
struct Cand {
    key: usize,
    plus_faces: BTreeSet<FaceId>,
    minus_faces: BTreeSet<FaceId>,
    pieces: Vec<Poly>,
}

/// Wall geometry shared with the connection stage: the wall's normal, its
/// slab along the normal and points spanning its volume.
#[derive(Debug, Clone)]
pub struct WallVolume {
    pub normal: DVec3,
    pub slab: (f64, f64),
    pub points: Vec<DVec3>,
    pub web: bool,
    pub length: f64,
}

impl WallVolume {
    /// From a wall feature's `shape` (as written by [`find_walls`]).
    pub fn of(f: &StiffnessFeature, up: DVec3, cos_tol: f64) -> Option<WallVolume> {
        let shape = f.shape.as_ref()?;
        let fz = shape.frame.z.normalize_or_zero();
        let fx = shape.frame.x.normalize_or_zero();
        let fy = fz.cross(fx);
        let to3 = |x: f64, y: f64, z: f64| shape.frame.origin + fx * x + fy * y + fz * z;
        let mut pts = Vec::new();
        let push_loop = |l: &ProfileLoop, pts: &mut Vec<DVec3>| {
            let n = l.vertices.len();
            for i in 0..n {
                let v = l.vertices[i];
                let w = l.vertices[(i + 1) % n];
                for z in [shape.z_min, shape.z_max] {
                    pts.push(to3(v.x, v.y, z));
                    if v.bulge != 0.0 {
                        let m = bulge_mid(DVec2::new(v.x, v.y), DVec2::new(w.x, w.y), v.bulge);
                        pts.push(to3(m.x, m.y, z));
                    }
                }
            }
        };
        push_loop(&shape.region.outer, &mut pts);
        let n = f.axis.normalize_or_zero();
        let planar = fz.dot(n).abs() > 0.999;
        let slab = if planar {
            let s0 = n.dot(shape.frame.origin);
            let (a, b) = (s0 + shape.z_min * fz.dot(n), s0 + shape.z_max * fz.dot(n));
            (a.min(b), a.max(b))
        } else {
            let t = f.thickness.unwrap_or(0.0);
            let centre = pts.iter().copied().sum::<DVec3>() / pts.len().max(1) as f64;
            let s0 = n.dot(centre);
            (s0 - 0.5 * t, s0 + 0.5 * t)
        };
        Some(WallVolume {
            normal: n,
            slab,
            points: pts,
            web: n.dot(up).abs() >= cos_tol,
            length: f.length,
        })
    }

    /// Range of the volume's points along `d`.
    pub fn range(&self, d: DVec3) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for p in &self.points {
            let s = d.dot(*p);
            lo = lo.min(s);
            hi = hi.max(s);
        }
        (lo, hi)
    }

    /// Where `other` lies relative to this wall's slab.
    pub fn side_of(&self, other: &WallVolume, tol: f64) -> SlabSide {
        let (lo, hi) = other.range(self.normal);
        let (a0, a1) = self.slab;
        if lo < a0 - tol && hi > a1 + tol {
            SlabSide::Through
        } else if hi <= a0 + tol || lo >= a1 - tol {
            SlabSide::Outside
        } else {
            SlabSide::Partly
        }
    }
}

/// Position of a wall's volume relative to another wall's slab.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlabSide {
    /// It continues past both sides of the slab.
    Through,
    /// It lies on one side, touching at most (it ends at the slab's face).
    Outside,
    /// It reaches into the slab and out on one side (an L corner, flush).
    Partly,
}

/// Finds the walls of the part (ids are assigned by the caller).
pub fn find_walls(
    brep: &Brep,
    adjacency: &[EdgeAdjacency],
    up: DVec3,
    k: &WallRecognition,
    warnings: &mut Vec<String>,
) -> Vec<StiffnessFeature> {
    let up = up.try_normalize().unwrap_or(DVec3::Z);
    let tol = k.distance_tolerance.max(1e-9);
    let ang = k.angle_tolerance_deg.to_radians();
    let cos_tol = ang.cos();
    let t_search = k.max_thickness.max(k.max_base_thickness);
    let tess_tol = TessTolerance {
        chord: 0.05,
        angle: 0.3,
    };

    let mut keys: Vec<Key> = Vec::new();
    let mut pairs: Vec<Pair> = Vec::new();
    let mut tris_cache: BTreeMap<FaceId, Tris> = BTreeMap::new();

    // ---- 1. planar pairs -------------------------------------------------
    let mut buckets: BTreeMap<(i64, i64, i64), (DVec3, Vec<PlaneFace>)> = BTreeMap::new();
    let q = 1.0 / ang.sin().max(1e-6);
    for (fi, f) in brep.faces.iter().enumerate() {
        if let Surface::Plane { frame } = &f.surface {
            let n = if f.same_sense { frame.z } else { -frame.z };
            let Some(n) = n.try_normalize() else { continue };
            let c = canonical(n);
            let key = (
                (c.x * q).round() as i64,
                (c.y * q).round() as i64,
                (c.z * q).round() as i64,
            );
            let e = buckets.entry(key).or_insert_with(|| (c, Vec::new()));
            e.1.push(PlaneFace {
                face: fi,
                s: e.0.dot(frame.origin),
                plus: n.dot(e.0) > 0.0,
            });
        }
    }
    // Per plane-pair key lookup.
    let mut key_of: BTreeMap<(usize, i64, i64), usize> = BTreeMap::new();
    let coarse = TessTolerance {
        chord: 0.5,
        angle: 0.5,
    };
    for (bi, (_, (c, faces))) in buckets.iter_mut().enumerate() {
        let c = *c;
        if !faces.iter().any(|p| p.plus) || faces.iter().all(|p| p.plus) {
            continue;
        }
        faces.sort_by(|x, y| x.s.total_cmp(&y.s).then(x.face.cmp(&y.face)));
        let frame = Frame::from_axis_ref(DVec3::ZERO, c, None);
        let to2 = |p: DVec3| DVec2::new(frame.x.dot(p), frame.y.dot(p));
        // 2D boxes from the loops (coarse polylines), no tessellation yet.
        let boxes: Vec<(DVec2, DVec2)> = faces
            .iter()
            .map(|pf| {
                let mut lo = DVec2::splat(f64::INFINITY);
                let mut hi = DVec2::splat(f64::NEG_INFINITY);
                for &l in &brep.faces[pf.face].loops {
                    for p in brep.loop_polyline(l, &coarse) {
                        let q = to2(p);
                        lo = lo.min(q);
                        hi = hi.max(q);
                    }
                }
                // Arcs between polyline points bulge by at most the chord.
                (
                    lo - DVec2::splat(coarse.chord),
                    hi + DVec2::splat(coarse.chord),
                )
            })
            .collect();
        let slices = Slices::new(faces, &boxes, tol);
        for (ai, a) in faces.iter().enumerate().filter(|(_, p)| p.plus) {
            let (amin, amax) = boxes[ai];
            // b behind a: s in [a.s - t_search - tol, a.s - tol).
            let mut cands: Vec<usize> = Vec::new();
            slices.query(a.s - t_search - tol, a.s - tol, amin, amax, &mut cands);
            cands.retain(|&j| !faces[j].plus);
            cands.sort_unstable();
            for bj in cands {
                let b = &faces[bj];
                tris_of(brep, a.face, &frame, &tess_tol, &mut tris_cache);
                tris_of(brep, b.face, &frame, &tess_tol, &mut tris_cache);
                let (ta, tb) = (&tris_cache[&a.face], &tris_cache[&b.face]);
                if !ta.overlaps_box(tb, -tol) {
                    continue;
                }
                let pieces = clip_all(ta, tb);
                let area: f64 = pieces.iter().map(|p| poly_area(p).abs()).sum();
                if area <= (tol * tol).max(1e-6) {
                    continue;
                }
                // Material between: no parallel face strictly between the
                // planes covering the largest shared piece's centroid.
                let probe = pieces
                    .iter()
                    .max_by(|x, y| poly_area(x).abs().total_cmp(&poly_area(y).abs()))
                    .map(|p| poly_centroid(p))
                    .unwrap_or_default();
                let mut between: Vec<usize> = Vec::new();
                slices.query(b.s + tol, a.s - tol, probe, probe, &mut between);
                between.sort_unstable();
                let mut blocked = false;
                for gj in between {
                    let g = faces[gj].face;
                    if g == a.face || g == b.face {
                        continue;
                    }
                    tris_of(brep, g, &frame, &tess_tol, &mut tris_cache);
                    if tris_cache[&g].contains(probe) {
                        blocked = true;
                        break;
                    }
                }
                if blocked {
                    continue;
                }
                let kk = (bi, quant(a.s, tol), quant(b.s, tol));
                let key = *key_of.entry(kk).or_insert_with(|| {
                    keys.push(Key {
                        kind: PairKind::Planes,
                        c,
                        frame,
                        s_plus: a.s,
                        s_minus: b.s,
                    });
                    keys.len() - 1
                });
                pairs.push(Pair {
                    a: a.face,
                    b: b.face,
                    key,
                    pieces,
                });
            }
        }
    }

    // ---- 2. coaxial cylinders ----------------------------------------------
    find_cylinder_pairs(brep, k, tol, cos_tol, &tess_tol, &mut keys, &mut pairs);

    // ---- 3. components per key, then bridging across crossing walls -------
    let mut cands = components(&pairs);
    let side_key = side_key_map(&cands, &keys);
    merge_across_crossings(&mut cands, &keys, &side_key, brep, adjacency, tol);

    // ---- 4./5. attributes and thinness ---------------------------------
    struct Built {
        cand: usize,
        feature: StiffnessFeature,
        thin: bool,
        base_ok: bool,
        vol: WallVolume,
    }
    let mut built: Vec<Built> = Vec::new();
    for (ci, cand) in cands.iter().enumerate() {
        let key = &keys[cand.key];
        let Some(mut f) = build_feature(brep, cand, key, up, cos_tol, k, warnings) else {
            continue;
        };
        let t = f.thickness.unwrap_or(0.0);
        let ratio = if t > 0.0 { f.height / t } else { 0.0 };
        let thin = t <= k.max_thickness + tol && ratio >= k.min_height_to_thickness;
        let is_web = f.axis.dot(up).abs() >= cos_tol;
        let base_ok = !thin
            && is_web
            && k.max_base_thickness > 0.0
            && t <= k.max_base_thickness + tol
            && ratio >= k.min_base_width_to_thickness;
        if !thin && !base_ok {
            continue;
        }
        f.provenance = f
            .provenance
            .with_value("height_to_thickness", ratio)
            .with_value("min_height_to_thickness", k.min_height_to_thickness)
            .with_value("max_thickness", k.max_thickness);
        if ratio >= k.careful_height_to_thickness {
            f.provenance.note = format!(
                "height/thickness {ratio:.1} above {:.0}: needs special care",
                k.careful_height_to_thickness
            );
        }
        let Some(vol) = WallVolume::of(&f, up, cos_tol) else {
            continue;
        };
        built.push(Built {
            cand: ci,
            feature: f,
            thin,
            base_ok,
            vol,
        });
    }

    // Which built walls touch (share an edge between side faces).
    let mut face_owner: BTreeMap<FaceId, Vec<usize>> = BTreeMap::new();
    for (i, b) in built.iter().enumerate() {
        for &fc in &b.feature.faces {
            face_owner.entry(fc).or_default().push(i);
        }
    }
    let touching = touching_pairs(adjacency, &face_owner);

    // Support bases: keep only when a thin wall touches them.
    let mut keep: Vec<bool> = built.iter().map(|b| b.thin).collect();
    for &(i, j) in &touching {
        for (x, y) in [(i, j), (j, i)] {
            if built[x].base_ok
                && built[y].thin
                && !built[y].vol.web
                && built[x].vol.side_of(&built[y].vol, tol.max(1e-3)) == SlabSide::Outside
            {
                keep[x] = true;
            }
        }
    }
    for (i, b) in built.iter_mut().enumerate() {
        if keep[i] && b.base_ok {
            b.feature.provenance.rule = RULE_SUPPORT.to_string();
            b.feature.provenance.note =
                "not thin itself; kept as the base web thin walls stand on".to_string();
        }
    }

    // ---- 6. roles ---------------------------------------------------------
    let mut flange = vec![false; built.len()];
    for &(i, j) in &touching {
        for (w, p) in [(i, j), (j, i)] {
            if keep[w] && keep[p] && !built[w].vol.web && built[p].vol.web {
                let side = built[w].vol.side_of(&built[p].vol, tol.max(1e-3));
                if side != SlabSide::Through {
                    flange[w] = true;
                }
            }
        }
    }
    let mut out = Vec::new();
    for (i, mut b) in built.into_iter().enumerate() {
        if !keep[i] {
            continue;
        }
        b.feature.role = Some(if b.vol.web {
            WallRole::Web
        } else if flange[i] {
            WallRole::Flange
        } else {
            WallRole::Rib
        });
        let _ = b.cand;
        out.push(b.feature);
    }
    out
}

/// Pairs `(i, j)`, `i < j`, of owners sharing an edge between their faces
/// or sharing a face.
pub(crate) fn touching_pairs(
    adjacency: &[EdgeAdjacency],
    face_owner: &BTreeMap<FaceId, Vec<usize>>,
) -> BTreeSet<(usize, usize)> {
    let mut out = BTreeSet::new();
    let empty = Vec::new();
    for owners in face_owner.values() {
        for &x in owners {
            for &y in owners {
                if x < y {
                    out.insert((x, y));
                }
            }
        }
    }
    for adj in adjacency {
        if adj.faces.len() < 2 {
            continue;
        }
        for (ii, &f) in adj.faces.iter().enumerate() {
            for &g in &adj.faces[ii + 1..] {
                let of = face_owner.get(&f).unwrap_or(&empty);
                let og = face_owner.get(&g).unwrap_or(&empty);
                for &x in of {
                    for &y in og {
                        if x != y {
                            out.insert((x.min(y), x.max(y)));
                        }
                    }
                }
            }
        }
    }
    out
}

/// The first non-zero component positive.
pub(crate) fn canonical(n: DVec3) -> DVec3 {
    let eps = 1e-9;
    let flip = if n.x.abs() > eps {
        n.x < 0.0
    } else if n.y.abs() > eps {
        n.y < 0.0
    } else {
        n.z < 0.0
    };
    if flip {
        -n
    } else {
        n
    }
}

fn quant(s: f64, tol: f64) -> i64 {
    (s / (10.0 * tol)).round() as i64
}

/// Tessellates a face into the 2D frame (x, y) of `frame` once (a planar
/// face belongs to one direction bucket, so the face index is the key).
fn tris_of(
    brep: &Brep,
    face: FaceId,
    frame: &Frame,
    tol: &TessTolerance,
    cache: &mut BTreeMap<FaceId, Tris>,
) {
    cache.entry(face).or_insert_with(|| {
        let to2 = |p: DVec3| DVec2::new(frame.x.dot(p), frame.y.dot(p));
        make_tris(brep, face, tol, to2)
    });
}

/// Faces of one direction bucket grouped by plane offset (slices), each
/// slice sorted by the 2D box's low x with the widest box remembered, so
/// that a box query touches only nearby faces.
/// One slice: (offset, entries (box min.x, face index in bucket), widest box).
type Slice = (f64, Vec<(f64, usize)>, f64);

struct Slices {
    slices: Vec<Slice>,
    boxes: Vec<(DVec2, DVec2)>,
}

impl Slices {
    fn new(faces: &[PlaneFace], boxes: &[(DVec2, DVec2)], tol: f64) -> Slices {
        let mut slices: Vec<Slice> = Vec::new();
        for (i, f) in faces.iter().enumerate() {
            let w = boxes[i].1.x - boxes[i].0.x;
            match slices.last_mut() {
                Some(sl) if (f.s - sl.0).abs() <= tol => {
                    sl.1.push((boxes[i].0.x, i));
                    sl.2 = sl.2.max(w);
                }
                _ => slices.push((f.s, vec![(boxes[i].0.x, i)], w)),
            }
        }
        for sl in &mut slices {
            sl.1.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
        Slices {
            slices,
            boxes: boxes.to_vec(),
        }
    }

    /// Faces with offset in `[s0, s1]` whose box meets `[lo, hi]`.
    fn query(&self, s0: f64, s1: f64, lo: DVec2, hi: DVec2, out: &mut Vec<usize>) {
        let start = self.slices.partition_point(|sl| sl.0 < s0);
        for sl in &self.slices[start..] {
            if sl.0 > s1 {
                break;
            }
            let from = sl.1.partition_point(|e| e.0 < lo.x - sl.2);
            for &(mx, i) in &sl.1[from..] {
                if mx > hi.x {
                    break;
                }
                let (bl, bh) = self.boxes[i];
                if bl.x <= hi.x && bh.x >= lo.x && bl.y <= hi.y && bh.y >= lo.y {
                    out.push(i);
                }
            }
        }
    }
}

fn make_tris(brep: &Brep, face: FaceId, tol: &TessTolerance, to2: impl Fn(DVec3) -> DVec2) -> Tris {
    let mut out = Tris {
        tris: Vec::new(),
        min: DVec2::splat(f64::INFINITY),
        max: DVec2::splat(f64::NEG_INFINITY),
    };
    if let Ok(m) = thinplan_brep::tessellate_face(brep, face, tol) {
        for t in &m.triangles {
            let mut tri = [
                to2(m.positions[t[0] as usize]),
                to2(m.positions[t[1] as usize]),
                to2(m.positions[t[2] as usize]),
            ];
            let a = (tri[1] - tri[0]).perp_dot(tri[2] - tri[0]);
            if a.abs() < 1e-14 {
                continue;
            }
            if a < 0.0 {
                tri.swap(1, 2);
            }
            for p in tri {
                out.min = out.min.min(p);
                out.max = out.max.max(p);
            }
            out.tris.push(tri);
        }
    }
    out
}

fn point_in_tri(p: DVec2, t: &[DVec2; 3]) -> bool {
    let d0 = (t[1] - t[0]).perp_dot(p - t[0]);
    let d1 = (t[2] - t[1]).perp_dot(p - t[1]);
    let d2 = (t[0] - t[2]).perp_dot(p - t[2]);
    d0 >= -1e-12 && d1 >= -1e-12 && d2 >= -1e-12
}

/// All non-empty intersections of triangles of `a` with triangles of `b`.
fn clip_all(a: &Tris, b: &Tris) -> Vec<Poly> {
    let mut out = Vec::new();
    for ta in &a.tris {
        let (amin, amax) = tri_box(ta);
        for tb in &b.tris {
            let (bmin, bmax) = tri_box(tb);
            if amin.x > bmax.x || bmin.x > amax.x || amin.y > bmax.y || bmin.y > amax.y {
                continue;
            }
            let p = clip_convex(ta, tb);
            if p.len() >= 3 && poly_area(&p).abs() > 1e-9 {
                out.push(p);
            }
        }
    }
    out
}

fn tri_box(t: &[DVec2; 3]) -> (DVec2, DVec2) {
    (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
}

/// Sutherland–Hodgman: triangle `a` clipped by counter-clockwise triangle `b`.
fn clip_convex(a: &[DVec2; 3], b: &[DVec2; 3]) -> Poly {
    let mut poly: Poly = a.to_vec();
    for i in 0..3 {
        let (e0, e1) = (b[i], b[(i + 1) % 3]);
        let d = e1 - e0;
        let inside = |p: DVec2| d.perp_dot(p - e0) >= 0.0;
        let mut next = Vec::with_capacity(poly.len() + 2);
        for j in 0..poly.len() {
            let p = poly[j];
            let q = poly[(j + 1) % poly.len()];
            let (ip, iq) = (inside(p), inside(q));
            if ip {
                next.push(p);
            }
            if ip != iq {
                let dp = d.perp_dot(p - e0);
                let dq = d.perp_dot(q - e0);
                let t = dp / (dp - dq);
                next.push(p + (q - p) * t);
            }
        }
        poly = next;
        if poly.len() < 3 {
            return Vec::new();
        }
    }
    poly
}

fn poly_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>() * 0.5
}

fn poly_centroid(p: &[DVec2]) -> DVec2 {
    let n = p.len().max(1);
    p.iter().copied().sum::<DVec2>() / n as f64
}

/// Connected components of faces linked by pairs, per key.
fn components(pairs: &[Pair]) -> Vec<Cand> {
    let mut by_key: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, p) in pairs.iter().enumerate() {
        by_key.entry(p.key).or_default().push(i);
    }
    let mut out = Vec::new();
    for (key, idx) in by_key {
        // Union-find over the pairs of this key through shared faces.
        let mut parent: Vec<usize> = (0..idx.len()).collect();
        let mut first_of_face: BTreeMap<FaceId, usize> = BTreeMap::new();
        for (li, &pi) in idx.iter().enumerate() {
            for fc in [pairs[pi].a, pairs[pi].b] {
                match first_of_face.get(&fc) {
                    Some(&o) => union(&mut parent, li, o),
                    None => {
                        first_of_face.insert(fc, li);
                    }
                }
            }
        }
        let mut groups: BTreeMap<usize, Cand> = BTreeMap::new();
        for (li, &pi) in idx.iter().enumerate() {
            let r = find(&mut parent, li);
            let c = groups.entry(r).or_insert_with(|| Cand {
                key,
                plus_faces: BTreeSet::new(),
                minus_faces: BTreeSet::new(),
                pieces: Vec::new(),
            });
            c.plus_faces.insert(pairs[pi].a);
            c.minus_faces.insert(pairs[pi].b);
            c.pieces.extend(pairs[pi].pieces.iter().cloned());
        }
        out.extend(groups.into_values());
    }
    out
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi] = lo;
    }
}

/// For every side face of a candidate: (key, plus side?).
fn side_key_map(cands: &[Cand], keys: &[Key]) -> BTreeMap<FaceId, Vec<(usize, bool)>> {
    let mut m: BTreeMap<FaceId, Vec<(usize, bool)>> = BTreeMap::new();
    for c in cands {
        if !matches!(keys[c.key].kind, PairKind::Planes) {
            continue;
        }
        for &f in &c.plus_faces {
            m.entry(f).or_default().push((c.key, true));
        }
        for &f in &c.minus_faces {
            m.entry(f).or_default().push((c.key, false));
        }
    }
    for v in m.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    m
}

/// Merges components on the same two planes that a crossing wall separates.
fn merge_across_crossings(
    cands: &mut Vec<Cand>,
    keys: &[Key],
    side_key: &BTreeMap<FaceId, Vec<(usize, bool)>>,
    brep: &Brep,
    adjacency: &[EdgeAdjacency],
    tol: f64,
) {
    // Faces of each candidate and the (other key, side) its faces touch.
    let mut face_cand: BTreeMap<FaceId, Vec<usize>> = BTreeMap::new();
    for (ci, c) in cands.iter().enumerate() {
        for &f in c.plus_faces.iter().chain(c.minus_faces.iter()) {
            face_cand.entry(f).or_default().push(ci);
        }
    }
    let mut touches: Vec<BTreeSet<(usize, bool)>> = vec![BTreeSet::new(); cands.len()];
    for adj in adjacency {
        for (ii, &f) in adj.faces.iter().enumerate() {
            for &g in &adj.faces[ii + 1..] {
                for (x, y) in [(f, g), (g, f)] {
                    if let (Some(cs), Some(ks)) = (face_cand.get(&x), side_key.get(&y)) {
                        for &ci in cs {
                            for &(k2, side) in ks {
                                if k2 != cands[ci].key {
                                    touches[ci].insert((k2, side));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    // Per key: index of (other key, side) → candidates touching it.
    let mut by_key: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (ci, c) in cands.iter().enumerate() {
        by_key.entry(c.key).or_default().push(ci);
    }
    let mut parent: Vec<usize> = (0..cands.len()).collect();
    for list in by_key.values() {
        if list.len() < 2 {
            continue;
        }
        let mut idx: BTreeMap<(usize, bool), Vec<usize>> = BTreeMap::new();
        for &ci in list {
            for &t in &touches[ci] {
                idx.entry(t).or_default().push(ci);
            }
        }
        for (&(k2, side), on_this) in &idx {
            if !side {
                continue;
            }
            let Some(on_other) = idx.get(&(k2, false)) else {
                continue;
            };
            let other = &keys[k2];
            if !matches!(other.kind, PairKind::Planes) {
                continue;
            }
            // c1 beyond the plus plane, c2 below the minus plane. The test
            // is separable, so every such pair (c1 ≠ c2) is joined by
            // joining all of them: the pairs of a complete bipartite graph
            // less self-pairs connect all its nodes as soon as one pair
            // exists. Linear in the lists (the panel's web pieces on one
            // rib line are many).
            let ok1: Vec<usize> = on_this
                .iter()
                .copied()
                .filter(|&c| cand_range(brep, &cands[c], other.c).0 >= other.s_plus - tol)
                .collect();
            let ok2: Vec<usize> = on_other
                .iter()
                .copied()
                .filter(|&c| cand_range(brep, &cands[c], other.c).1 <= other.s_minus + tol)
                .collect();
            let any_pair = ok1.iter().any(|&a| ok2.iter().any(|&b| a != b));
            if any_pair {
                let anchor = ok1[0];
                for &c in ok1.iter().chain(ok2.iter()) {
                    union(&mut parent, anchor, c);
                }
            }
        }
    }
    let mut merged: BTreeMap<usize, Cand> = BTreeMap::new();
    for (ci, c) in cands.iter().enumerate() {
        let r = find(&mut parent, ci);
        let c = c.clone();
        match merged.get_mut(&r) {
            Some(m) => {
                m.plus_faces.extend(c.plus_faces);
                m.minus_faces.extend(c.minus_faces);
                m.pieces.extend(c.pieces);
            }
            None => {
                merged.insert(r, c);
            }
        }
    }
    *cands = merged.into_values().collect();
}

/// Range of a candidate's side-face vertices along `d`.
fn cand_range(brep: &Brep, c: &Cand, d: DVec3) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &f in c.plus_faces.iter().chain(c.minus_faces.iter()) {
        for &l in &brep.faces[f].loops {
            for ce in &brep.loops[l].coedges {
                let e = &brep.edges[ce.edge];
                for v in [e.start, e.end] {
                    let s = d.dot(brep.vertices[v].point);
                    lo = lo.min(s);
                    hi = hi.max(s);
                }
            }
        }
    }
    (lo, hi)
}

/// Attributes, shape and provenance of a candidate wall (role left empty).
fn build_feature(
    brep: &Brep,
    cand: &Cand,
    key: &Key,
    up: DVec3,
    cos_tol: f64,
    k: &WallRecognition,
    warnings: &mut Vec<String>,
) -> Option<StiffnessFeature> {
    let mut faces: Vec<FaceId> = cand
        .plus_faces
        .iter()
        .chain(cand.minus_faces.iter())
        .copied()
        .collect();
    faces.sort_unstable();
    faces.dedup();
    let pts2: Vec<DVec2> = cand.pieces.iter().flatten().copied().collect();
    if pts2.is_empty() {
        return None;
    }
    match key.kind {
        PairKind::Planes => {
            let c = key.c;
            let t = key.s_plus - key.s_minus;
            let s_mid = 0.5 * (key.s_plus + key.s_minus);
            let to3 = |p: DVec2| key.frame.x * p.x + key.frame.y * p.y + c * s_mid;
            let pts3: Vec<DVec3> = pts2.iter().map(|p| to3(*p)).collect();
            let web = c.dot(up).abs() >= cos_tol;
            let (xdir, height, length) = if web {
                // In-plane extents along the frame axes.
                // In-plane extents; the height is the smaller extent or the
                // mean width (area / length), whichever is less, so that a
                // frame of strips is not taken for a plate.
                let (ex, ey) = extent2(&pts2);
                let area: f64 = cand.pieces.iter().map(|p| poly_area(p).abs()).sum();
                let (d, w, l) = if ex >= ey {
                    (key.frame.x, ey, ex)
                } else {
                    (key.frame.y, ex, ey)
                };
                (d, w.min(if l > 0.0 { area / l } else { 0.0 }), l)
            } else {
                let h = (up - c * c.dot(up)).normalize();
                let l = c.cross(h).normalize();
                (l, span(&pts3, h), span(&pts3, l))
            };
            let origin = to3(poly_centroid(&pts2));
            let origin = origin - c * (c.dot(origin) - s_mid);
            let yd = c.cross(xdir);
            let region = side_region(brep, cand, key, origin, xdir, yd, &pts3)
                .unwrap_or_else(|| rect_region(&pts3, origin, xdir, yd));
            let shape = Prism {
                frame: PrismFrame {
                    origin,
                    x: xdir,
                    z: c,
                },
                region,
                z_min: -0.5 * t,
                z_max: 0.5 * t,
            };
            let prov = Provenance::new(ProvenanceSource::Recogniser, RULE_PLANES)
                .with_value("thickness", t)
                .with_value("height", height)
                .with_value("length", length)
                .with_value(
                    "shared_area",
                    cand.pieces.iter().map(|p| poly_area(p).abs()).sum(),
                );
            Some(StiffnessFeature {
                id: StiffnessFeatureId(0),
                kind: StiffnessKind::Wall,
                role: None,
                faces,
                axis: c,
                thickness: Some(t),
                height,
                length,
                diameter: None,
                shape: Some(shape),
                access: Vec::new(),
                provenance: prov,
            })
        }
        PairKind::Cylinders {
            frame,
            outer,
            inner,
        } => {
            // pts2: (r_mid * θ, axial) with θ relative to frame.x.
            let t = outer - inner;
            let rm = 0.5 * (outer + inner);
            let (mut th0, mut th1) = (f64::INFINITY, f64::NEG_INFINITY);
            let (mut z0, mut z1) = (f64::INFINITY, f64::NEG_INFINITY);
            for p in &pts2 {
                th0 = th0.min(p.x / rm);
                th1 = th1.max(p.x / rm);
                z0 = z0.min(p.y);
                z1 = z1.max(p.y);
            }
            let thm = 0.5 * (th0 + th1);
            let normal = canonical(frame.x * thm.cos() + frame.y * thm.sin());
            let axis_up = frame.z.dot(up).abs() >= cos_tol;
            let arc_len = rm * (th1 - th0);
            let (height, length) = if axis_up {
                (z1 - z0, arc_len)
            } else {
                (arc_len.min(z1 - z0), arc_len.max(z1 - z0))
            };
            let sweep = th1 - th0;
            if sweep >= std::f64::consts::TAU - 1e-6 {
                warnings.push(format!(
                    "curved wall on faces {faces:?} is a closed tube; its profile is given as a sector"
                ));
            }
            let sweep = sweep.min(std::f64::consts::TAU - 1e-3);
            let pt = |r: f64, th: f64| DVec2::new(r * th.cos(), r * th.sin());
            let b = (sweep / 4.0).tan();
            let a0 = pt(outer, th0);
            let a1 = pt(outer, th0 + sweep);
            let b1 = pt(inner, th0 + sweep);
            let b0 = pt(inner, th0);
            let region = Region {
                outer: ProfileLoop {
                    vertices: vec![
                        ProfileVertex {
                            x: a0.x,
                            y: a0.y,
                            bulge: b,
                        },
                        ProfileVertex {
                            x: a1.x,
                            y: a1.y,
                            bulge: 0.0,
                        },
                        ProfileVertex {
                            x: b1.x,
                            y: b1.y,
                            bulge: -b,
                        },
                        ProfileVertex {
                            x: b0.x,
                            y: b0.y,
                            bulge: 0.0,
                        },
                    ],
                },
                holes: Vec::new(),
            };
            let shape = Prism {
                frame: PrismFrame {
                    origin: frame.origin,
                    x: frame.x,
                    z: frame.z,
                },
                region,
                z_min: z0,
                z_max: z1,
            };
            let _ = k;
            let prov = Provenance::new(ProvenanceSource::Recogniser, RULE_CYLINDERS)
                .with_value("thickness", t)
                .with_value("height", height)
                .with_value("length", length)
                .with_value("outer_radius", outer)
                .with_value("inner_radius", inner);
            Some(StiffnessFeature {
                id: StiffnessFeatureId(0),
                kind: StiffnessKind::Wall,
                role: None,
                faces,
                axis: normal,
                thickness: Some(t),
                height,
                length,
                diameter: None,
                shape: Some(shape),
                access: Vec::new(),
                provenance: prov,
            })
        }
    }
}

fn extent2(p: &[DVec2]) -> (f64, f64) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for q in p {
        lo = lo.min(*q);
        hi = hi.max(*q);
    }
    (hi.x - lo.x, hi.y - lo.y)
}

fn span(p: &[DVec3], d: DVec3) -> f64 {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for q in p {
        let s = d.dot(*q);
        lo = lo.min(s);
        hi = hi.max(s);
    }
    (hi - lo).max(0.0)
}

/// The shared region's bounding rectangle in the wall frame.
fn rect_region(p: &[DVec3], origin: DVec3, x: DVec3, y: DVec3) -> Region {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for q in p {
        let d = *q - origin;
        let v = DVec2::new(d.dot(x), d.dot(y));
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let v = |x: f64, y: f64| ProfileVertex { x, y, bulge: 0.0 };
    Region {
        outer: ProfileLoop {
            vertices: vec![v(lo.x, lo.y), v(hi.x, lo.y), v(hi.x, hi.y), v(lo.x, hi.y)],
        },
        holes: Vec::new(),
    }
}

/// The exact loops (lines and arcs) of the smaller side when it is one face.
fn side_region(
    brep: &Brep,
    cand: &Cand,
    key: &Key,
    origin: DVec3,
    x: DVec3,
    y: DVec3,
    _pts: &[DVec3],
) -> Option<Region> {
    let area = |fs: &BTreeSet<FaceId>, frame: &Frame| -> f64 {
        fs.iter()
            .map(|&f| {
                let t = make_tris(brep, f, &TessTolerance::default(), |p| {
                    DVec2::new(frame.x.dot(p), frame.y.dot(p))
                });
                t.tris.iter().map(|t| poly_area(t).abs()).sum::<f64>()
            })
            .sum()
    };
    let side = if cand.plus_faces.len() == 1 && cand.minus_faces.len() == 1 {
        if area(&cand.plus_faces, &key.frame) <= area(&cand.minus_faces, &key.frame) {
            &cand.plus_faces
        } else {
            &cand.minus_faces
        }
    } else if cand.plus_faces.len() == 1 {
        &cand.plus_faces
    } else if cand.minus_faces.len() == 1 {
        &cand.minus_faces
    } else {
        return None;
    };
    let face = *side.iter().next()?;
    let z = x.cross(y);
    let to2 = |p: DVec3| {
        let d = p - origin;
        DVec2::new(d.dot(x), d.dot(y))
    };
    let mut loops: Vec<ProfileLoop> = Vec::new();
    for &l in &brep.faces[face].loops {
        let lp = &brep.loops[l];
        let mut verts: Vec<(DVec2, f64)> = Vec::new();
        for ce in &lp.coedges {
            let e = &brep.edges[ce.edge];
            let start = to2(brep.vertices[brep.coedge_start(*ce)].point);
            match &e.curve {
                thinplan_brep::Curve::Line { .. } => verts.push((start, 0.0)),
                thinplan_brep::Curve::Circle { frame, .. } => {
                    let (t0, t1) = brep.edge_param_range(ce.edge);
                    let mut sweep = t1 - t0;
                    if !ce.forward {
                        sweep = -sweep;
                    }
                    if frame.z.dot(z) < 0.0 {
                        sweep = -sweep;
                    }
                    if e.is_closed() {
                        // Two half arcs, through the point half-way round.
                        let (a, b) = if ce.forward { (t0, t1) } else { (t1, t0) };
                        let mid = to2(e.curve.point(a + 0.5 * (b - a)));
                        let hb = (sweep / 8.0).tan();
                        verts.push((start, hb));
                        verts.push((mid, hb));
                    } else {
                        verts.push((start, (sweep / 4.0).tan()));
                    }
                }
                _ => {
                    // Other curves: their polyline as straight pieces.
                    let poly = brep.coedge_polyline(*ce, &TessTolerance::default());
                    for p in &poly[..poly.len() - 1] {
                        verts.push((to2(*p), 0.0));
                    }
                }
            }
        }
        if !lp.orientation {
            // Reverse: vertex i+1..i with negated bulges.
            let n = verts.len();
            let mut rev = Vec::with_capacity(n);
            for i in (0..n).rev() {
                let next = (i + 1) % n;
                rev.push((verts[next].0, -verts[i].1));
            }
            verts = rev;
        }
        if verts.len() >= 2 {
            loops.push(ProfileLoop {
                vertices: verts
                    .into_iter()
                    .map(|(p, b)| ProfileVertex {
                        x: p.x,
                        y: p.y,
                        bulge: b,
                    })
                    .collect(),
            });
        }
    }
    if loops.is_empty() {
        return None;
    }
    let areas: Vec<f64> = loops.iter().map(loop_area).collect();
    let oi = (0..loops.len()).max_by(|&a, &b| areas[a].abs().total_cmp(&areas[b].abs()))?;
    let mut outer = loops[oi].clone();
    if areas[oi] < 0.0 {
        outer = reverse_loop(&outer);
    }
    let mut holes = Vec::new();
    for (i, l) in loops.iter().enumerate() {
        if i == oi {
            continue;
        }
        holes.push(if areas[i] > 0.0 {
            reverse_loop(l)
        } else {
            l.clone()
        });
    }
    Some(Region { outer, holes })
}

fn reverse_loop(l: &ProfileLoop) -> ProfileLoop {
    let n = l.vertices.len();
    let mut v = Vec::with_capacity(n);
    for i in (0..n).rev() {
        let next = l.vertices[(i + 1) % n];
        v.push(ProfileVertex {
            x: next.x,
            y: next.y,
            bulge: -l.vertices[i].bulge,
        });
    }
    ProfileLoop { vertices: v }
}

/// Signed area of a loop with bulges (positive counter-clockwise).
pub(crate) fn loop_area(l: &ProfileLoop) -> f64 {
    let n = l.vertices.len();
    let mut a = 0.0;
    for i in 0..n {
        let p = l.vertices[i];
        let q = l.vertices[(i + 1) % n];
        a += 0.5 * (p.x * q.y - q.x * p.y);
        if p.bulge != 0.0 {
            // Circular segment between chord and arc, signed by the bulge.
            let chord = ((q.x - p.x).powi(2) + (q.y - p.y).powi(2)).sqrt();
            let theta = 4.0 * p.bulge.atan();
            if theta.abs() > 1e-12 && chord > 0.0 {
                let r = chord / (2.0 * (theta / 2.0).sin()).abs();
                a += 0.5 * r * r * (theta - theta.sin());
            }
        }
    }
    a
}

/// The midpoint of the arc from `p` to `q` with `bulge`.
pub(crate) fn bulge_mid(p: DVec2, q: DVec2, bulge: f64) -> DVec2 {
    let m = 0.5 * (p + q);
    let d = q - p;
    // Sagitta = bulge * chord / 2, to the right of the chord for positive bulge
    // when going counter-clockwise (the arc bows to the right of p→q).
    let n = DVec2::new(d.y, -d.x);
    m + n * (0.5 * bulge)
}

/// Pairs of coaxial cylinders (convex outer, concave inner).
fn find_cylinder_pairs(
    brep: &Brep,
    k: &WallRecognition,
    tol: f64,
    cos_tol: f64,
    tess_tol: &TessTolerance,
    keys: &mut Vec<Key>,
    pairs: &mut Vec<Pair>,
) {
    struct Cyl {
        face: FaceId,
        frame: Frame,
        r: f64,
        convex: bool,
    }
    let mut cyls: Vec<Cyl> = Vec::new();
    for (fi, f) in brep.faces.iter().enumerate() {
        if let Surface::Cylinder { frame, radius } = &f.surface {
            cyls.push(Cyl {
                face: fi,
                frame: *frame,
                r: *radius,
                convex: f.same_sense,
            });
        }
    }
    if cyls.len() < 2 {
        return;
    }
    // Group by axis line: canonical direction and the axis point closest to
    // the origin, quantised; sort within by radius.
    let q = 1.0 / (1.0 - cos_tol).max(1e-9).sqrt();
    type AxisKey = (i64, i64, i64, i64, i64, i64);
    let mut groups: BTreeMap<AxisKey, Vec<usize>> = BTreeMap::new();
    let qd = 1.0 / (100.0 * tol);
    for (i, c) in cyls.iter().enumerate() {
        let d = canonical(c.frame.z.normalize());
        let o = c.frame.origin - d * d.dot(c.frame.origin);
        groups
            .entry((
                (d.x * q).round() as i64,
                (d.y * q).round() as i64,
                (d.z * q).round() as i64,
                (o.x * qd).round() as i64,
                (o.y * qd).round() as i64,
                (o.z * qd).round() as i64,
            ))
            .or_default()
            .push(i);
    }
    let mut key_of: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for list in groups.values() {
        for &oi in list {
            let o = &cyls[oi];
            if !o.convex {
                continue;
            }
            for &ii in list {
                let inn = &cyls[ii];
                if inn.convex || inn.r >= o.r - tol || o.r - inn.r > k.max_thickness + tol {
                    continue;
                }
                let axis = canonical(o.frame.z.normalize());
                let frame = Frame::from_axis_ref(
                    o.frame.origin - axis * axis.dot(o.frame.origin),
                    axis,
                    Some(o.frame.x),
                );
                let rm = 0.5 * (o.r + inn.r);
                let unroll = |p: DVec3| {
                    let d = p - frame.origin;
                    let th = d.dot(frame.y).atan2(d.dot(frame.x));
                    DVec2::new(rm * th, d.dot(frame.z))
                };
                let ta = make_tris(brep, o.face, tess_tol, unroll);
                let tb = make_tris(brep, inn.face, tess_tol, unroll);
                // Triangles straddling the ±π cut are dropped by the area
                // test below only when they flip; skip wide ones.
                let fix = |t: Tris| Tris {
                    tris: t
                        .tris
                        .into_iter()
                        .filter(|tr| {
                            let (lo, hi) = tri_box(tr);
                            hi.x - lo.x < rm * std::f64::consts::PI
                        })
                        .collect(),
                    ..t
                };
                let (ta, tb) = (fix(ta), fix(tb));
                if !ta.overlaps_box(&tb, 0.0) {
                    continue;
                }
                let pieces = clip_all(&ta, &tb);
                let area: f64 = pieces.iter().map(|p| poly_area(p).abs()).sum();
                if area <= 1e-6 {
                    continue;
                }
                let key = *key_of.entry((oi, ii)).or_insert_with(|| {
                    keys.push(Key {
                        kind: PairKind::Cylinders {
                            frame,
                            outer: o.r,
                            inner: inn.r,
                        },
                        c: axis,
                        frame,
                        s_plus: o.r,
                        s_minus: inn.r,
                    });
                    keys.len() - 1
                });
                pairs.push(Pair {
                    a: o.face,
                    b: inn.face,
                    key,
                    pieces,
                });
            }
        }
    }
}
