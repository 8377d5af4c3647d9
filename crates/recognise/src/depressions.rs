//! Depressions (holes, cut-outs, slots, notches, pockets, steps) and details
//! (chamfers, fillets), thesis §5.4.1 and §6.1.1.
//!
//! # Algorithm
//!
//! All faces are read, also those of walls: walls and depressions may share
//! faces (a slot beside a thin slab keeps the slab's side as its own side).
//! "The wall wins" (thesis figure 5.8) is applied afterwards, precisely: a
//! face set whose faces, apart from corner blends and the end faces of
//! standing walls, all belong to walls (a web face as floor, wall sides as
//! sides: the space between isogrid ribs, or between two ribs on a web) is
//! the space between walls, not a
//! depression, and is dropped (with a warning only when it is ambiguous:
//! no web face among them); its corner blends become fillet details. A set
//! with at least one face no wall owns stays a depression.
//!
//! 1. **Envelope faces.** A planar face with the whole part behind its plane
//!    lies on the convex hull: a face of the stock envelope (or a chamfer on
//!    it). Every other face (a planar face with material in front of it, a
//!    cylinder or cone with material outside) is a *depression face*.
//! 2. **Depression face sets.** Depression faces are joined across concave
//!    and tangent edges into connected sets (the classic "concave edge"
//!    grouping: a subtractive feature's faces meet one another at concave
//!    edges and the rest of the part at convex ones).
//! 3. **Frame.** Each set is read in the frame of an axis: the normal of its
//!    *floor* (a planar face no other face of the set turns against, with
//!    most sides perpendicular to it, preferring a normal parallel to an
//!    envelope face), or without a floor the common perpendicular of its
//!    sides (a through opening).
//! 4. **Topology and shape.** The sides (faces of the set other than
//!    floors) form a closed ring around the axis or an open chain. Closed
//!    with a floor: pocket; closed without: hole (round when its sides are
//!    one cylinder, else a free-shaped passage; a passage with two parallel
//!    straight sides joined by two ends, at least `min_slot_length_to_width`
//!    times as long as wide, is a slot, `recognise.slot.opening`). Open
//!    with a floor: one side is a step (slanted when the side leans away
//!    from the floor), two
//!    facing sides a slot, two sides meeting at a corner a blind step, three
//!    or more a blind slot; open without a floor: two sides a V slot (or a
//!    notch at a right angle), more a cut-out. The profile (the floor's
//!    outline, or the hull of the sides' projection) becomes the feature's
//!    [`Prism`]; its corner count and the corner angles are recorded.
//! 5. **Details.** A narrow planar face with convex edges, inclined to the
//!    neighbours along its two long edges, is a chamfer; a cylindrical blend
//!    (concave or convex, tangent to its neighbours, radius at most the
//!    knowledge's limit) that no depression took is a fillet. Details are
//!    read only on faces no wall lists.
//! 6. **Details on a wall's corner** (figure 4.10). A planar face across a
//!    standing wall (next to both its sides, inside its slab, all edges
//!    convex) joining two faces square to the wall (its top and end) and
//!    inclined to both is a chamfer of any length
//!    (`recognise.chamfer.wall_corner`), as long as each leg cuts at most
//!    `max_chamfer_width_ratio` of the face it shortens (a roof of two
//!    inclined tops is no chamfer). Such a chamfer, and a convex fillet
//!    (a cylinder along the wall normal) across a wall's corner, get as
//!    shape the wedge they remove: in the wall's frame, the corner where
//!    the two joined faces' planes meet and the detail's two ends (the
//!    fillet's side an arc), swept over the wall's prism. Values: `leg_a`,
//!    `leg_b` (corner to each end), `corner_x`, `corner_y` (the corner in
//!    the wall's frame). `connect` makes the detail a leaf of that wall.
//!    Concave blends (between walls) add material and get no shape.
//!
//! Cost: face facts, sets and readings are linear in the faces (sets are
//! read in time quadratic in their own size); the envelope test computes
//! the support value `max p·n` over the part's boundary points once per
//! distinct plane direction, and coplanar lookups go through planes sorted
//! by offset per direction.
//!
//! Nothing here depends on `up`: depressions are classified in their own
//! frame (roles, which depend on the set-up, are for walls).
//!
//! Every feature's provenance records the rule (`recognise.pocket`,
//! `recognise.step.slanted`, …) and the values it used: `sides` (planar
//! sides), `curved_sides`, `floor` (0/1), `closed` (0/1), `profile_corners`
//! (corners of the profile), `floor_corners`, `right_corners` (1 when all
//! side–side corners are right angles), `min_corner_deg`, `slanted`,
//! `depth`, and for long through openings `opening_length`, `opening_width`.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_brep::{Brep, Convexity, EdgeAdjacency, FaceId};
use thinplan_knowledge::{DepressionKind, DepressionRecognition};
use thinplan_plan::{
    Prism, PrismFrame, ProfileLoop, ProfileVertex, Provenance, ProvenanceSource, Region,
    StiffnessFeature, StiffnessFeatureId, StiffnessKind, WallRole,
};

mod geom;

use geom::{convex_hull, face_facts, frame_for, polygon_corners, signed_area, FaceFacts, FaceGeom};

/// Finds depressions and details on all faces of `brep`; `walls` (the wall
/// recogniser's features, may be empty) decide which face sets are the space
/// between walls (dropped: the wall wins) and which faces may carry details
/// (only faces no wall owns). Ids are assigned by the caller.
pub fn find_depressions(
    brep: &Brep,
    adjacency: &[EdgeAdjacency],
    _up: DVec3,
    k: &DepressionRecognition,
    walls: &[StiffnessFeature],
    warnings: &mut Vec<String>,
) -> Vec<StiffnessFeature> {
    let facts = face_facts(brep, adjacency, k.distance_tolerance.max(1e-9));
    let mut wall_face = vec![WallFace::None; brep.faces.len()];
    for w in walls.iter().filter(|w| w.kind == StiffnessKind::Wall) {
        let web = w.role == Some(WallRole::Web);
        for &f in &w.faces {
            if let Some(x) = wall_face.get_mut(f) {
                *x = match (*x, web) {
                    (WallFace::None | WallFace::Web, true) => WallFace::Web,
                    (WallFace::None | WallFace::Side, false) => WallFace::Side,
                    _ => WallFace::Both,
                };
            }
        }
    }
    let wall_end = wall_ends(walls, &facts, &wall_face, k);
    // Envelope directions (distinct) and planar faces by direction, sorted
    // by offset: the per-face lookups stay logarithmic.
    let mut hull_normals: Vec<DVec3> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    let mut planes: BTreeMap<[i64; 3], Vec<(f64, FaceId)>> = BTreeMap::new();
    for (f, fx) in facts.iter().enumerate() {
        if let FaceGeom::Plane { normal, origin } = fx.geom {
            let key = geom::direction_key(normal);
            if fx.hull && seen.insert(key) {
                hull_normals.push(normal);
            }
            planes.entry(key).or_default().push((origin.dot(normal), f));
        }
    }
    for list in planes.values_mut() {
        list.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
    let r = Reader {
        hull_normals,
        planes,
        brep,
        facts: &facts,
        k,
        wall_face: &wall_face,
        wall_end: &wall_end,
        walls,
        sin_tol: k.angle_tolerance_deg.to_radians().sin(),
        cos_tol: k.angle_tolerance_deg.to_radians().cos(),
    };
    r.run(warnings)
}

struct Reader<'a> {
    /// The distinct normals of envelope faces.
    hull_normals: Vec<DVec3>,
    /// Planar faces by direction key, sorted by plane offset.
    planes: BTreeMap<[i64; 3], Vec<(f64, FaceId)>>,
    brep: &'a Brep,
    facts: &'a [FaceFacts],
    k: &'a DepressionRecognition,
    /// Which wall (if any) lists each face.
    wall_face: &'a [WallFace],
    /// Faces walls do not list that are their ends or tops (planar, square
    /// to the wall, inside its slab, next to its sides).
    wall_end: &'a [bool],
    /// The walls found before (details on their corners get a shape).
    walls: &'a [StiffnessFeature],
    /// Sine of the angle tolerance: `|a·b|` below it is perpendicular,
    /// above `1 −` it parallel.
    sin_tol: f64,
    /// Cosine of the angle tolerance: `a·b` above it is parallel.
    cos_tol: f64,
}

/// The end and top faces of planar standing walls: faces next to both of a
/// wall's sides, planar, square to the wall normal, lying inside its slab. They belong to
/// the wall's solid though the wall does not list them (a rib's end at the
/// rim of the web it stands on).
fn wall_ends(
    walls: &[StiffnessFeature],
    facts: &[FaceFacts],
    wall_face: &[WallFace],
    k: &DepressionRecognition,
) -> Vec<bool> {
    let mut end = vec![false; facts.len()];
    let tol = k.distance_tolerance.max(1e-6) * 10.0;
    let sin_tol = k.angle_tolerance_deg.to_radians().sin();
    // Standing walls only: a web's slab may be thick (a support base) and
    // hold the sides of depressions cut into it.
    for w in walls
        .iter()
        .filter(|w| w.kind == StiffnessKind::Wall && w.role != Some(WallRole::Web))
    {
        let (Some(t), Some(shape)) = (w.thickness, w.shape.as_ref()) else {
            continue;
        };
        let n = shape.frame.z;
        if n.dot(w.axis).abs() < 1.0 - sin_tol {
            continue; // a curved wall: its frame is the cylinder's
        }
        let o = shape.frame.origin;
        for &f in &w.faces {
            let Some(fx) = facts.get(f) else { continue };
            for nb in &fx.neighbours {
                let g = nb.face;
                if end[g] || wall_face[g] != WallFace::None {
                    continue;
                }
                let gx = &facts[g];
                let square = gx.geom.normal().is_some_and(|m| m.dot(n).abs() < sin_tol);
                // Next to both sides: two of the wall's faces on either side
                // of its mid-plane.
                let sides = gx
                    .neighbours
                    .iter()
                    .filter(|m| w.faces.contains(&m.face))
                    .map(|m| {
                        facts[m.face]
                            .geom
                            .normal()
                            .map_or(0, |q| q.dot(n).signum() as i32)
                    })
                    .collect::<Vec<i32>>();
                let both = sides.contains(&1) && sides.contains(&-1);
                if square
                    && both
                    && gx
                        .points
                        .iter()
                        .all(|p| (*p - o).dot(n).abs() <= 0.5 * t + tol)
                {
                    end[g] = true;
                }
            }
        }
    }
    end
}

/// How a face belongs to walls.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WallFace {
    None,
    /// A face of a web (a wall whose normal is along `up`).
    Web,
    /// A side face of a standing wall (rib, flange).
    Side,
    /// Both (a face two walls list).
    Both,
}

/// What one depression face set was read as.
struct Reading {
    kind: DepressionKind,
    rule: &'static str,
    axis: DVec3,
    faces: Vec<FaceId>,
    values: Vec<(&'static str, f64)>,
    shape: Option<Prism>,
    height: f64,
    length: f64,
    diameter: Option<f64>,
}

impl Reader<'_> {
    fn run(&self, warnings: &mut Vec<String>) -> Vec<StiffnessFeature> {
        let n = self.brep.faces.len();
        let free = |f: FaceId| self.wall_face[f] == WallFace::None;
        let is_dep: Vec<bool> = (0..n).map(|f| self.is_depression_face(f)).collect();
        // Connected sets over concave and tangent edges.
        let mut comp = vec![usize::MAX; n];
        let mut sets: Vec<Vec<FaceId>> = Vec::new();
        for s in 0..n {
            if !is_dep[s] || comp[s] != usize::MAX {
                continue;
            }
            let id = sets.len();
            let mut set = vec![s];
            comp[s] = id;
            let mut i = 0;
            while i < set.len() {
                let f = set[i];
                for nb in &self.facts[f].neighbours {
                    if is_dep[nb.face]
                        && comp[nb.face] == usize::MAX
                        && matches!(nb.convexity, Convexity::Concave | Convexity::Smooth)
                    {
                        comp[nb.face] = id;
                        set.push(nb.face);
                    }
                }
                i += 1;
            }
            set.sort_unstable();
            sets.push(set);
        }
        let mut readings = Vec::new();
        let mut used = vec![false; n];
        for set in &sets {
            if let Some(ambiguous) = self.between_walls(set) {
                if ambiguous {
                    self.warn_between_walls(set, warnings);
                }
                continue;
            }
            for r in self.read_set(set) {
                if let Some(ambiguous) = self.between_walls(&r.faces) {
                    if ambiguous {
                        self.warn_between_walls(&r.faces, warnings);
                    }
                    continue;
                }
                for &f in &r.faces {
                    used[f] = true;
                }
                readings.push(r);
            }
        }
        // Details on what is left.
        for (f, u) in used.iter_mut().enumerate() {
            if *u || !free(f) {
                continue;
            }
            let read = self
                .read_corner_chamfer(f)
                .or_else(|| self.read_chamfer(f))
                .or_else(|| self.read_fillet(f));
            if let Some(mut r) = read {
                if r.shape.is_none() {
                    self.shape_on_wall_corner(f, &mut r);
                }
                *u = true;
                readings.push(r);
            }
        }
        readings.retain(|r| self.k.recognises(r.kind));
        if readings.is_empty() && !sets.is_empty() {
            warnings.push(format!(
                "depressions: {} depression face set(s) matched no enabled kind",
                sets.len()
            ));
        }
        readings.into_iter().map(into_feature).collect()
    }

    /// A concave cylindrical corner blend (a fillet candidate): radius at
    /// most the knowledge's limit, tangent to a neighbour, not a full turn.
    fn is_blend(&self, f: FaceId) -> bool {
        let fx = &self.facts[f];
        matches!(fx.geom, FaceGeom::Cylinder { radius, .. } if radius <= self.k.max_fillet_radius)
            && fx
                .neighbours
                .iter()
                .any(|nb| nb.convexity == Convexity::Smooth && nb.face != f)
            && !self.full_turn(&[f])
    }

    /// The wall-wins test: `Some(ambiguous)` when every face of `faces`
    /// other than corner blends and walls' end faces is a face of a wall, and
    /// at least one is (the space between walls,
    /// not a depression); `ambiguous` when no web face is among them (no
    /// floor a web provides: say so to the planner). `None`: a depression.
    fn between_walls(&self, faces: &[FaceId]) -> Option<bool> {
        let mut core = 0usize;
        let mut web = false;
        for &f in faces {
            if self.is_blend(f) || self.wall_end[f] {
                continue;
            }
            core += 1;
            match self.wall_face[f] {
                WallFace::None => return None,
                WallFace::Web | WallFace::Both => web = true,
                WallFace::Side => {}
            }
        }
        (core > 0).then_some(!web)
    }

    fn warn_between_walls(&self, faces: &[FaceId], warnings: &mut Vec<String>) {
        let read = self
            .read_one(faces)
            .map(|r| format!("{:?}", r.kind).to_lowercase())
            .unwrap_or_else(|| "nothing".into());
        warnings.push(format!(
            "depressions: faces {faces:?} (readable as {read}) lie on the sides of walls with no web \
             between them; read as the space between walls, not a depression (the wall wins)"
        ));
    }

    /// A face that bounds removed material: not on the envelope.
    fn is_depression_face(&self, f: FaceId) -> bool {
        let fx = &self.facts[f];
        match fx.geom {
            FaceGeom::Plane { .. } => {
                !fx.hull
                    && fx
                        .neighbours
                        .iter()
                        .any(|nb| matches!(nb.convexity, Convexity::Concave | Convexity::Smooth))
            }
            FaceGeom::Cylinder { hole, .. } | FaceGeom::Cone { hole, .. } => hole,
            FaceGeom::Other => false,
        }
    }

    fn parallel(&self, a: DVec3, b: DVec3) -> bool {
        a.dot(b) > self.cos_tol
    }

    fn perpendicular(&self, a: DVec3, b: DVec3) -> bool {
        a.dot(b).abs() < self.sin_tol
    }

    /// Whether the part has an envelope face with its normal along `a` (±).
    fn principal(&self, a: DVec3) -> bool {
        self.hull_normals
            .iter()
            .any(|n| n.dot(a).abs() > self.cos_tol)
    }

    /// Whether another planar face lies in the plane of face `f` (normal
    /// `n`): looked up among the faces of the same direction by offset.
    fn coplanar_other(&self, f: FaceId, n: DVec3, origin: DVec3, tol: f64) -> bool {
        let Some(list) = self.planes.get(&geom::direction_key(n)) else {
            return false;
        };
        let d = origin.dot(n);
        let start = list.partition_point(|(e, _)| *e < d - tol);
        list[start..]
            .iter()
            .take_while(|(e, _)| *e <= d + tol)
            .any(|(_, g)| *g != f)
    }

    /// Adjacent through a concave or tangent edge.
    fn joined(&self, a: FaceId, b: FaceId) -> bool {
        self.facts[a].neighbours.iter().any(|nb| {
            nb.face == b && matches!(nb.convexity, Convexity::Concave | Convexity::Smooth)
        })
    }

    /// Picks the floor of a set: `(face, score)`.
    fn floor_of(&self, set: &[FaceId]) -> Option<FaceId> {
        let mut best: Option<((usize, bool, i64), FaceId)> = None;
        for &f in set {
            let Some(a) = self.facts[f].geom.normal() else {
                continue;
            };
            let mut ok = true;
            let mut perp = 0usize;
            let mut joined_side = false;
            for &g in set {
                if g == f {
                    continue;
                }
                match self.facts[g].geom {
                    FaceGeom::Plane { normal, .. } => {
                        let d = normal.dot(a);
                        if d < -self.sin_tol {
                            ok = false;
                        } else if self.perpendicular(normal, a) {
                            perp += 1;
                        }
                    }
                    FaceGeom::Cylinder { axis, .. } | FaceGeom::Cone { axis, .. } => {
                        if axis.dot(a).abs() > self.cos_tol {
                            perp += 1;
                        }
                    }
                    FaceGeom::Other => {}
                }
                if self.joined(f, g) {
                    joined_side = true;
                }
            }
            // A floor is parallel to the envelope or square to a side (else
            // two inclined faces are the sides of a V).
            if !ok || (!joined_side && set.len() > 1) || (perp == 0 && !self.principal(a)) {
                continue;
            }
            let area = (geom::loop_area(&self.facts[f].outer) * 1e3) as i64;
            let key = (perp, self.principal(a), area);
            if best.as_ref().is_none_or(|(b, _)| key > *b) {
                best = Some((key, f));
            }
        }
        best.map(|(_, f)| f)
    }

    /// Common perpendicular of the sides of a set without a floor.
    fn through_axis(&self, set: &[FaceId]) -> Option<DVec3> {
        let mut dirs: Vec<DVec3> = Vec::new();
        for &f in set {
            match self.facts[f].geom {
                FaceGeom::Cylinder { axis, .. } | FaceGeom::Cone { axis, .. } => return Some(axis),
                FaceGeom::Plane { normal, .. } => dirs.push(normal),
                FaceGeom::Other => {}
            }
        }
        let mut best: Option<(usize, DVec3)> = None;
        for i in 0..dirs.len() {
            for j in i + 1..dirs.len() {
                let c = dirs[i].cross(dirs[j]);
                if c.length() < 0.05 {
                    continue;
                }
                let a = c.normalize();
                let count = dirs.iter().filter(|d| self.perpendicular(**d, a)).count();
                if best.is_none_or(|(b, _)| count > b) {
                    best = Some((count, a));
                }
            }
        }
        best.map(|(_, a)| canonical(a))
    }

    /// Splits faces into sets connected through concave or tangent edges.
    fn connected_parts(&self, faces: &[FaceId]) -> Vec<Vec<FaceId>> {
        let mut left: Vec<FaceId> = faces.to_vec();
        let mut out = Vec::new();
        while let Some(s) = left.pop() {
            let mut part = vec![s];
            let mut i = 0;
            while i < part.len() {
                let f = part[i];
                let (join, keep): (Vec<FaceId>, Vec<FaceId>) =
                    left.iter().partition(|&&g| self.joined(f, g));
                part.extend(join);
                left = keep;
                i += 1;
            }
            part.sort_unstable();
            out.push(part);
        }
        out.sort();
        out
    }

    fn read_set(&self, set: &[FaceId]) -> Vec<Reading> {
        if self.floor_of(set).is_none() {
            if let Some(axis) = self.through_axis(set) {
                // Through openings along different axes that meet (crossing
                // passages): read the faces along this axis alone, then the rest.
                let (along, rest): (Vec<FaceId>, Vec<FaceId>) =
                    set.iter().partition(|&&f| match self.facts[f].geom {
                        FaceGeom::Plane { normal, .. } => self.perpendicular(normal, axis),
                        _ => true,
                    });
                if !rest.is_empty() && along.len() >= 2 {
                    let mut out = Vec::new();
                    for part in self
                        .connected_parts(&along)
                        .into_iter()
                        .chain(self.connected_parts(&rest))
                    {
                        out.extend(self.read_set(&part));
                    }
                    return out;
                }
            }
        }
        self.read_one(set).into_iter().collect()
    }

    fn read_one(&self, set: &[FaceId]) -> Option<Reading> {
        // A lone blend between claimed faces is a fillet, not a depression.
        if set.len() == 1 {
            if let FaceGeom::Cylinder { .. } = self.facts[set[0]].geom {
                if !self.full_turn(set) {
                    if let Some(r) = self.read_fillet(set[0]) {
                        return Some(r);
                    }
                }
            }
        }
        let floor = self.floor_of(set);
        let axis = match floor {
            Some(f) => self.facts[f].geom.normal()?,
            None => self.through_axis(set)?,
        };
        let floors: Vec<FaceId> = set
            .iter()
            .copied()
            .filter(|&f| {
                floor.is_some()
                    && self.facts[f]
                        .geom
                        .normal()
                        .is_some_and(|n| self.parallel(n, axis))
            })
            .collect();
        let sides: Vec<FaceId> = set
            .iter()
            .copied()
            .filter(|f| !floors.contains(f))
            .collect();
        let planar_sides: Vec<FaceId> = sides
            .iter()
            .copied()
            .filter(|&f| matches!(self.facts[f].geom, FaceGeom::Plane { .. }))
            .collect();
        let curved = sides.len() - planar_sides.len();
        // Ring or chain: degrees in the side graph.
        let degree = |f: FaceId| {
            sides
                .iter()
                .filter(|&&g| g != f && self.joined(f, g))
                .count()
        };
        let closed = if sides.is_empty() {
            false
        } else if curved == sides.len() && planar_sides.is_empty() {
            self.full_turn(&sides)
        } else {
            sides.len() >= 3 && sides.iter().all(|&f| degree(f) >= 2)
                || (sides.len() == 2 && self.full_turn(&sides))
        };
        // Corner angles between planar sides meeting at concave edges.
        let mut min_corner = 180.0f64;
        let mut right = true;
        let mut corners = 0;
        for (i, &a) in planar_sides.iter().enumerate() {
            for &b in &planar_sides[i + 1..] {
                if !self.joined(a, b) {
                    continue;
                }
                let (na, nb) = (
                    self.facts[a].geom.normal().unwrap_or(DVec3::Z),
                    self.facts[b].geom.normal().unwrap_or(DVec3::Z),
                );
                // Interior angle of the removed region's profile at the corner.
                let pa = (na - axis * na.dot(axis)).normalize_or_zero();
                let pb = (nb - axis * nb.dot(axis)).normalize_or_zero();
                let angle = 180.0 - pa.dot(pb).clamp(-1.0, 1.0).acos().to_degrees();
                min_corner = min_corner.min(angle);
                corners += 1;
                if (angle - 90.0).abs() > self.k.right_angle_tolerance_deg {
                    right = false;
                }
            }
        }
        if corners == 0 {
            right = false;
        }
        // A side leaning away from the floor, or a one-sided step whose faces
        // are inclined to the envelope while its floor is not a triangle
        // cut off a corner.
        let leaning = planar_sides.iter().any(|&f| {
            self.facts[f]
                .geom
                .normal()
                .is_some_and(|n| n.dot(axis) > self.sin_tol)
        });
        let tilted = floor.is_some()
            && planar_sides.len() == 1
            && set.iter().any(|&f| {
                self.facts[f]
                    .geom
                    .normal()
                    .is_some_and(|n| !self.principal(n))
            });
        // Profile and depth in the axis frame.
        let pts: Vec<DVec3> = set
            .iter()
            .flat_map(|&f| self.facts[f].points.iter().copied())
            .collect();
        let origin = floor
            .map(|f| self.facts[f].points[0])
            .unwrap_or_else(|| pts.iter().copied().sum::<DVec3>() / pts.len().max(1) as f64);
        let frame = frame_for(axis, origin);
        let local: Vec<DVec3> = pts.iter().map(|p| frame.to_local(*p)).collect();
        let z_min = local.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        let z_max = local.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
        let tol = self.k.distance_tolerance.max(1e-6) * 10.0;
        let (profile, floor_corners) = match floor {
            Some(f) => {
                let outline: Vec<DVec2> = self.facts[f]
                    .outer
                    .iter()
                    .map(|p| frame.to_local(*p).truncate())
                    .collect();
                let c = polygon_corners(&outline, tol);
                let n = c.len();
                (c, n)
            }
            None => (
                polygon_corners(
                    &convex_hull(local.iter().map(|p| p.truncate()).collect()),
                    tol,
                ),
                0,
            ),
        };
        let mut profile = profile;
        if signed_area(&profile) < 0.0 {
            profile.reverse();
        }
        let profile_corners = profile.len();
        let slanted = leaning || (tilted && floor_corners != 3);
        let has_floor = floor.is_some();
        // Coplanar pieces (a side cut in two by a crossing feature) are one side.
        let mut planes: Vec<(DVec3, f64)> = Vec::new();
        for &f in &planar_sides {
            if let FaceGeom::Plane { normal, origin } = self.facts[f].geom {
                let d = normal.dot(origin);
                if !planes
                    .iter()
                    .any(|(n, e)| self.parallel(*n, normal) && (d - e).abs() <= tol)
                {
                    planes.push((normal, d));
                }
            }
        }
        let n_sides = planes.len();
        let plane_of = |f: FaceId| match self.facts[f].geom {
            FaceGeom::Plane { normal, origin } => planes.iter().position(|(n, e)| {
                self.parallel(*n, normal) && (normal.dot(origin) - e).abs() <= tol
            }),
            _ => None,
        };
        // Sides all on one cylinder: a round hole (whole, or cut open by
        // another feature).
        let diameter = match sides.first().map(|&f| self.facts[f].geom) {
            Some(FaceGeom::Cylinder {
                axis: a0,
                origin: o0,
                radius: r0,
                ..
            }) if curved == sides.len() => {
                let coaxial = sides.iter().all(|&f| match self.facts[f].geom {
                    FaceGeom::Cylinder {
                        axis,
                        origin,
                        radius,
                        ..
                    } => {
                        let d = origin - o0;
                        axis.dot(a0).abs() > self.cos_tol
                            && (d - a0 * d.dot(a0)).length() <= tol
                            && (radius - r0).abs() <= tol
                    }
                    _ => false,
                });
                coaxial.then_some(2.0 * r0)
            }
            _ => None,
        };
        // A through opening with two parallel straight sides joined by two
        // ends (round or straight), long for its width: a slot.
        let elongation = if closed && !has_floor && diameter.is_none() {
            self.elongation(&planes, &sides, curved, axis, &pts)
        } else {
            None
        };
        let opening_slot =
            elongation.is_some_and(|(l, w)| l >= self.k.min_slot_length_to_width * w);
        use DepressionKind::*;
        let (kind, rule) = if diameter.is_some() {
            if has_floor {
                (Hole, "recognise.hole.blind")
            } else {
                (Hole, "recognise.hole.round")
            }
        } else if closed {
            match (has_floor, diameter.is_some()) {
                (false, true) => (Hole, "recognise.hole.round"),
                (false, false) if opening_slot => (Slot, "recognise.slot.opening"),
                (false, false) => (Hole, "recognise.hole.passage"),
                (true, true) => (Hole, "recognise.hole.blind"),
                (true, false) => (Pocket, "recognise.pocket"),
            }
        } else if has_floor {
            match n_sides + curved {
                0 => return None,
                1 if slanted => (Step, "recognise.step.slanted"),
                1 => (Step, "recognise.step.through"),
                2 => {
                    // The two sides (each perhaps in pieces) meet at a corner.
                    let adjacent = sides.iter().any(|&a| {
                        sides.iter().any(|&b| {
                            plane_of(a).is_some() && plane_of(a) != plane_of(b) && self.joined(a, b)
                        })
                    });
                    if !adjacent {
                        (Slot, "recognise.slot.through")
                    } else if right {
                        (Step, "recognise.step.blind")
                    } else {
                        (Step, "recognise.step.two_sided")
                    }
                }
                _ => (Slot, "recognise.slot.blind"),
            }
        } else {
            match n_sides + curved {
                0 | 1 => (Notch, "recognise.notch"),
                2 if right => (Notch, "recognise.notch"),
                2 => (Slot, "recognise.slot.v"),
                _ => (Cutout, "recognise.cutout"),
            }
        };
        let shape = (profile.len() >= 3).then(|| Prism {
            frame: PrismFrame {
                origin: frame.origin,
                x: frame.x,
                z: frame.z,
            },
            region: Region {
                outer: ProfileLoop {
                    vertices: profile
                        .iter()
                        .map(|p| ProfileVertex {
                            x: p.x,
                            y: p.y,
                            bulge: 0.0,
                        })
                        .collect(),
                },
                holes: Vec::new(),
            },
            z_min,
            z_max,
        });
        let (lo, hi) = profile.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let length = (hi - lo).max_element().max(0.0);
        let mut values = vec![
            ("sides", n_sides as f64),
            ("curved_sides", curved as f64),
            ("floor", has_floor as u8 as f64),
            ("closed", closed as u8 as f64),
            ("profile_corners", profile_corners as f64),
            ("floor_corners", floor_corners as f64),
            ("right_corners", right as u8 as f64),
            ("min_corner_deg", if corners > 0 { min_corner } else { 0.0 }),
            ("slanted", slanted as u8 as f64),
            ("depth", z_max - z_min),
        ];
        if let Some(d) = diameter {
            values.push(("diameter", d));
        }
        if let Some((l, w)) = elongation {
            values.push(("opening_length", l));
            values.push(("opening_width", w));
        }
        Some(Reading {
            kind,
            rule,
            axis,
            faces: set.to_vec(),
            values,
            shape,
            height: z_max - z_min,
            length,
            diameter,
        })
    }

    /// `(length, width)` of a through opening whose outline is two parallel
    /// straight sides joined by two ends: two planes facing each other plus
    /// two curved ends (a stadium), or two pairs of facing planes (a
    /// rectangle; the closer pair are the long sides). `planes` are the
    /// distinct planes of the planar sides.
    fn elongation(
        &self,
        planes: &[(DVec3, f64)],
        sides: &[FaceId],
        curved: usize,
        axis: DVec3,
        pts: &[DVec3],
    ) -> Option<(f64, f64)> {
        let facing = |a: usize, b: usize| planes[a].0.dot(planes[b].0) < -self.cos_tol;
        // Distance between two facing planes n·x = d0 and −n·x = d1.
        let gap = |a: usize, b: usize| (planes[a].1 + planes[b].1).abs();
        let (long_a, width) = match (planes.len(), curved) {
            (2, 2) => {
                let ends_round = sides.iter().all(|&f| {
                    matches!(
                        self.facts[f].geom,
                        FaceGeom::Plane { .. } | FaceGeom::Cylinder { .. }
                    )
                });
                if !ends_round || !facing(0, 1) {
                    return None;
                }
                (0, gap(0, 1))
            }
            (4, 0) => {
                let partner = |a: usize| (0..4).find(|&b| b != a && facing(a, b));
                let b = partner(0)?;
                let rest: Vec<usize> = (1..4).filter(|&i| i != b).collect();
                if !facing(rest[0], rest[1]) {
                    return None;
                }
                let (g0, g1) = (gap(0, b), gap(rest[0], rest[1]));
                if g0 <= g1 {
                    (0, g0)
                } else {
                    (rest[0], g1)
                }
            }
            _ => return None,
        };
        let dir = planes[long_a].0.cross(axis).try_normalize()?;
        let (lo, hi) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let t = p.dot(dir);
                (lo.min(t), hi.max(t))
            });
        (width > 0.0 && hi > lo).then_some((hi - lo, width))
    }

    /// Whether curved faces together turn all the way round their axis
    /// (a full hole wall).
    fn full_turn(&self, faces: &[FaceId]) -> bool {
        let mut sweep = 0.0;
        for &f in faces {
            let FaceGeom::Cylinder { axis, origin, .. } = self.facts[f].geom else {
                return false;
            };
            let frame = frame_for(axis, origin);
            let mut angles: Vec<f64> = self.facts[f]
                .points
                .iter()
                .map(|p| {
                    let l = frame.to_local(*p);
                    l.y.atan2(l.x)
                })
                .collect();
            angles.sort_by(f64::total_cmp);
            // The largest angular gap not covered by the face.
            let mut gap: f64 = 0.0;
            for w in angles.windows(2) {
                gap = gap.max(w[1] - w[0]);
            }
            if let (Some(a), Some(b)) = (angles.first(), angles.last()) {
                gap = gap.max(a + std::f64::consts::TAU - b);
            }
            sweep += std::f64::consts::TAU - gap;
        }
        sweep > std::f64::consts::TAU - 0.2
    }

    /// A narrow planar face with convex edges, inclined to the faces along
    /// its two long edges.
    fn read_chamfer(&self, f: FaceId) -> Option<Reading> {
        let fx = &self.facts[f];
        let n = fx.geom.normal()?;
        if fx.neighbours.is_empty()
            || fx
                .neighbours
                .iter()
                .any(|nb| !matches!(nb.convexity, Convexity::Convex))
        {
            return None;
        }
        // The two longest straight edges.
        let mut edges: Vec<(f64, usize)> = fx
            .neighbours
            .iter()
            .enumerate()
            .map(|(i, nb)| {
                let e = &self.brep.edges[nb.edge];
                let a = self.brep.vertices[e.start].point;
                let b = self.brep.vertices[e.end].point;
                (a.distance(b), i)
            })
            .collect();
        edges.sort_by(|a, b| b.0.total_cmp(&a.0));
        if edges.len() < 2 {
            return None;
        }
        let lo = self.k.min_chamfer_incline_deg.to_radians();
        let inclined = |i: usize| {
            let g = fx.neighbours[i].face;
            self.facts[g].geom.normal().is_some_and(|m| {
                let ang = n.dot(m).clamp(-1.0, 1.0).acos();
                ang > lo && ang < std::f64::consts::FRAC_PI_2 - lo
            })
        };
        // The long edges: the longest, and the longest one parallel to it.
        let e0 = &self.brep.edges[fx.neighbours[edges[0].1].edge];
        let d0 = (self.brep.vertices[e0.end].point - self.brep.vertices[e0.start].point)
            .normalize_or_zero();
        let other = edges[1..].iter().find(|(_, i)| {
            let e = &self.brep.edges[fx.neighbours[*i].edge];
            let d = (self.brep.vertices[e.end].point - self.brep.vertices[e.start].point)
                .normalize_or_zero();
            d.dot(d0).abs() > self.cos_tol
        })?;
        if !inclined(edges[0].1) || !inclined(other.1) {
            return None;
        }
        let p0 = self.brep.vertices[e0.start].point;
        let width = fx
            .points
            .iter()
            .map(|p| {
                let v = *p - p0;
                (v - d0 * v.dot(d0)).length()
            })
            .fold(0.0, f64::max);
        // On the envelope (an edge of the stock cut off) the width may also
        // be relative to the length.
        let limit = if fx.hull {
            self.k
                .max_chamfer_width
                .max(self.k.max_chamfer_width_ratio * edges[0].0)
        } else {
            self.k.max_chamfer_width
        };
        if width > limit {
            return None;
        }
        // A piece of a face split by a feature (coplanar with another face)
        // is not a chamfer.
        if let FaceGeom::Plane { origin, .. } = fx.geom {
            let tol = self.k.distance_tolerance.max(1e-6) * 10.0;
            if self.coplanar_other(f, n, origin, tol) {
                return None;
            }
        }
        Some(Reading {
            kind: DepressionKind::Chamfer,
            rule: "recognise.chamfer",
            axis: n,
            faces: vec![f],
            values: vec![("width", width), ("length", edges[0].0)],
            shape: None,
            height: width,
            length: edges[0].0,
            diameter: None,
        })
    }

    /// A cylindrical blend of small radius, tangent to a neighbour.
    fn read_fillet(&self, f: FaceId) -> Option<Reading> {
        let fx = &self.facts[f];
        let FaceGeom::Cylinder {
            axis, radius, hole, ..
        } = fx.geom
        else {
            return None;
        };
        if radius > self.k.max_fillet_radius
            || !fx
                .neighbours
                .iter()
                .any(|nb| nb.convexity == Convexity::Smooth && nb.face != f)
            || self.full_turn(&[f])
        {
            return None;
        }
        Some(Reading {
            kind: DepressionKind::Fillet,
            rule: if hole {
                "recognise.fillet.concave"
            } else {
                "recognise.fillet.convex"
            },
            axis,
            faces: vec![f],
            values: vec![("radius", radius), ("concave", hole as u8 as f64)],
            shape: None,
            height: 0.0,
            length: 0.0,
            diameter: None,
        })
    }

    /// Figure 4.10: a planar face cut across a standing wall's corner (next
    /// to both sides, all edges convex), inclined to the two faces it joins
    /// (the wall's top and end): a chamfer on the wall, whatever its length
    /// (a large chamfer is still a detail, thesis §4.1.3). Each leg is at
    /// most `max_chamfer_width_ratio` of the face it cuts short, so a roof
    /// of two inclined tops is no chamfer.
    fn read_corner_chamfer(&self, f: FaceId) -> Option<Reading> {
        let fx = &self.facts[f];
        let n = fx.geom.normal()?;
        if fx
            .neighbours
            .iter()
            .any(|nb| !matches!(nb.convexity, Convexity::Convex))
        {
            return None;
        }
        let c = self.wall_corner(f)?;
        let lo = self.k.min_chamfer_incline_deg.to_radians();
        let inclined = c.joins.iter().all(|&g| {
            self.facts[g].geom.normal().is_some_and(|m| {
                let ang = n.dot(m).clamp(-1.0, 1.0).acos();
                ang > lo && ang < std::f64::consts::FRAC_PI_2 - lo
            })
        });
        // The corner it replaces lies outside the face (a convex cut).
        let n2 = DVec2::new(n.dot(c.fx), n.dot(c.fy));
        if !inclined || !c.legs_ok(self.k) || n2.dot(c.corner - c.ends[0]) <= 0.0 {
            return None;
        }
        let mut r = Reading {
            kind: DepressionKind::Chamfer,
            rule: "recognise.chamfer.wall_corner",
            axis: n,
            faces: vec![f],
            values: Vec::new(),
            shape: None,
            height: c.t,
            length: c.ends[0].distance(c.ends[1]),
            diameter: None,
        };
        r.values = vec![("width", c.t), ("length", r.length)];
        r.shape = Some(c.wedge(None));
        r.values.extend(c.values());
        Some(r)
    }

    /// Gives a detail read on face `f` its wedge when `f` lies across a
    /// standing wall's corner: a chamfer (planar) or a convex fillet (a
    /// cylinder along the wall normal); concave blends between walls add
    /// material and have none.
    fn shape_on_wall_corner(&self, f: FaceId, r: &mut Reading) {
        let arc = match self.facts[f].geom {
            FaceGeom::Plane { .. } => None,
            FaceGeom::Cylinder {
                axis,
                origin,
                radius,
                hole: false,
            } => Some((axis, origin, radius)),
            _ => return,
        };
        let Some(c) = self.wall_corner(f) else { return };
        if !c.legs_ok(self.k) {
            return;
        }
        let arc = match arc {
            None => None,
            Some((axis, origin, radius)) => {
                if axis.dot(c.n).abs() < self.cos_tol {
                    return;
                }
                let q = c.to2(origin);
                // Convex: the corner lies outside the cylinder.
                if c.corner.distance(q) <= radius {
                    return;
                }
                Some(q)
            }
        };
        r.shape = Some(c.wedge(arc));
        r.values.extend(c.values());
    }

    /// The standing wall whose corner face `f` lies across: next to both of
    /// its sides, inside its slab, joining exactly two other planar faces
    /// square to the wall (its top and end).
    fn wall_corner(&self, f: FaceId) -> Option<WallCorner> {
        let fx = &self.facts[f];
        let tol = self.k.distance_tolerance.max(1e-6) * 10.0;
        for w in self
            .walls
            .iter()
            .filter(|w| w.kind == StiffnessKind::Wall && w.role != Some(WallRole::Web))
        {
            let (Some(t), Some(shape)) = (w.thickness, w.shape.as_ref()) else {
                continue;
            };
            let n = shape.frame.z.normalize_or_zero();
            if n.dot(w.axis.normalize_or_zero()).abs() < self.cos_tol {
                continue; // a curved wall
            }
            let mid = shape.frame.origin + n * (0.5 * (shape.z_min + shape.z_max));
            let mut sides = (false, false);
            let mut joins: Vec<FaceId> = Vec::new();
            let mut ok = true;
            for nb in &fx.neighbours {
                if w.faces.contains(&nb.face) {
                    let s = self.facts[nb.face].geom.normal().map_or(0.0, |m| m.dot(n));
                    if s > 0.0 {
                        sides.0 = true;
                    } else if s < 0.0 {
                        sides.1 = true;
                    }
                } else if !joins.contains(&nb.face) {
                    let square = self.facts[nb.face]
                        .geom
                        .normal()
                        .is_some_and(|m| self.perpendicular(m, n));
                    ok &= square;
                    joins.push(nb.face);
                }
            }
            if !(ok && sides.0 && sides.1 && joins.len() == 2)
                || fx
                    .points
                    .iter()
                    .any(|p| (*p - mid).dot(n).abs() > 0.5 * t + tol)
            {
                continue;
            }
            let fxd = shape.frame.x.normalize_or_zero();
            let mut c = WallCorner {
                origin: shape.frame.origin,
                fx: fxd,
                fy: n.cross(fxd),
                n,
                z: (shape.z_min, shape.z_max),
                t,
                joins: [joins[0], joins[1]],
                ends: [DVec2::ZERO; 2],
                corner: DVec2::ZERO,
                legs: [0.0; 2],
                rest: [0.0; 2],
            };
            // Each joined face: where the detail meets it (the shared edge,
            // which runs across the wall) and its trace in the wall plane.
            let mut dirs = [DVec2::ZERO; 2];
            let joins = c.joins;
            for (k, &g) in joins.iter().enumerate() {
                let nb = fx.neighbours.iter().find(|nb| nb.face == g)?;
                let e = &self.brep.edges[nb.edge];
                c.ends[k] = c.to2(self.brep.vertices[e.start].point);
                let m = self.facts[g].geom.normal()?;
                let d = n.cross(m);
                dirs[k] = DVec2::new(d.dot(c.fx), d.dot(c.fy)).try_normalize()?;
            }
            let den = dirs[0].perp_dot(dirs[1]);
            if den.abs() < self.sin_tol {
                continue; // parallel top and end: no corner
            }
            let s = (c.ends[1] - c.ends[0]).perp_dot(dirs[1]) / den;
            c.corner = c.ends[0] + dirs[0] * s;
            for (k, dir) in dirs.iter().enumerate() {
                c.legs[k] = c.corner.distance(c.ends[k]);
                let (lo, hi) = self.facts[c.joins[k]]
                    .points
                    .iter()
                    .map(|p| c.to2(*p).dot(*dir))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                        (lo.min(v), hi.max(v))
                    });
                c.rest[k] = (hi - lo).max(0.0);
            }
            if c.legs.iter().any(|l| *l <= tol) {
                continue;
            }
            return Some(c);
        }
        None
    }
}

/// A detail across a standing wall's corner, in the wall's shape frame
/// (x, y in the wall plane, z its normal).
struct WallCorner {
    origin: DVec3,
    fx: DVec3,
    fy: DVec3,
    n: DVec3,
    /// The wall prism's extent along its normal (the wedge's sweep).
    z: (f64, f64),
    t: f64,
    /// The two faces the detail joins (the wall's top and end).
    joins: [FaceId; 2],
    /// Where the detail meets each joined face (2D).
    ends: [DVec2; 2],
    /// The corner the detail replaces: where the joined faces' planes meet.
    corner: DVec2,
    /// Corner to each end.
    legs: [f64; 2],
    /// What is left of each joined face along its trace.
    rest: [f64; 2],
}

impl WallCorner {
    fn to2(&self, p: DVec3) -> DVec2 {
        let v = p - self.origin;
        DVec2::new(v.dot(self.fx), v.dot(self.fy))
    }

    /// A detail cuts a corner short, not a face away: each leg at most
    /// `max_chamfer_width_ratio` of the face's length before the cut.
    fn legs_ok(&self, k: &DepressionRecognition) -> bool {
        (0..2).all(|i| self.legs[i] <= k.max_chamfer_width_ratio * (self.legs[i] + self.rest[i]))
    }

    fn values(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("leg_a", self.legs[0]),
            ("leg_b", self.legs[1]),
            ("corner_x", self.corner.x),
            ("corner_y", self.corner.y),
        ]
    }

    /// The wedge the detail removes: the corner and the detail's two ends
    /// (the detail's side an arc about `centre` for a fillet), counter-
    /// clockwise, swept over the wall's thickness.
    fn wedge(&self, centre: Option<DVec2>) -> Prism {
        let (a, c, b) = (self.ends[0], self.corner, self.ends[1]);
        let (a, b) = if (c - a).perp_dot(b - a) > 0.0 {
            (a, b)
        } else {
            (b, a)
        };
        // Loop a → c → b, then back to a along the detail (b's bulge).
        let bulge = centre.map_or(0.0, |q| {
            let (ra, rb) = (a - q, b - q);
            let sweep = ra.angle_to(rb).abs();
            let d = a - b;
            let right = DVec2::new(d.y, -d.x);
            let s = if right.dot(c - (a + b) * 0.5) > 0.0 {
                1.0
            } else {
                -1.0
            };
            s * (sweep / 4.0).tan()
        });
        let v = |p: DVec2, bulge: f64| ProfileVertex {
            x: p.x,
            y: p.y,
            bulge,
        };
        Prism {
            frame: PrismFrame {
                origin: self.origin,
                x: self.fx,
                z: self.n,
            },
            region: Region {
                outer: ProfileLoop {
                    vertices: vec![v(a, 0.0), v(c, 0.0), v(b, bulge)],
                },
                holes: Vec::new(),
            },
            z_min: self.z.0,
            z_max: self.z.1,
        }
    }
}

/// A direction with its first significant component positive (through
/// openings have no preferred sense).
fn canonical(a: DVec3) -> DVec3 {
    for c in [a.x, a.y, a.z] {
        if c.abs() > 1e-9 {
            return if c < 0.0 { -a } else { a };
        }
    }
    a
}

fn into_feature(r: Reading) -> StiffnessFeature {
    let kind = match r.kind {
        DepressionKind::Hole => StiffnessKind::Hole,
        DepressionKind::Cutout => StiffnessKind::Cutout,
        DepressionKind::Slot => StiffnessKind::Slot,
        DepressionKind::Notch => StiffnessKind::Notch,
        DepressionKind::Pocket => StiffnessKind::Pocket,
        DepressionKind::Step => StiffnessKind::Step,
        DepressionKind::Chamfer => StiffnessKind::Chamfer,
        DepressionKind::Fillet => StiffnessKind::Fillet,
    };
    let mut provenance = Provenance::new(ProvenanceSource::Recogniser, r.rule);
    for (name, v) in r.values {
        provenance = provenance.with_value(name, v);
    }
    StiffnessFeature {
        id: StiffnessFeatureId(0),
        kind,
        role: None,
        faces: r.faces,
        axis: r.axis,
        thickness: None,
        height: r.height,
        length: r.length,
        diameter: r.diameter,
        shape: r.shape,
        access: Vec::new(),
        provenance,
    }
}
