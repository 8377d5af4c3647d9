//! Stage 6, resolve: the machining features of stage 5 made
//! interference-free along the set-up's tool-access direction, the
//! remaining material turned into further features, per-edge adjacency
//! decided against the sequence, and accessibility constraints added
//! (thesis §5.4.2, §6.2.3; DESIGN.md stage 6).
//!
//! The blank (the part's bounding box in the set-up frame) is cut into
//! horizontal slabs at every height where the part or a feature changes
//! (B-rep vertices, feature bounds; finer where faces slope). In each slab
//! the part's section is constant for a prismatic part, so the material to
//! remove is `blank − section`, exactly. Each feature of stage 5 becomes a
//! plan-view region swept over its height range (its *claim*); per slab,
//! claims take `claim ∩ (blank − section)` minus what higher-ranked claims
//! already took (`interference.ron`). What no claim takes is remaining
//! material, owned by a depression, the web under it or the nearest wall.
//! Pieces that are the same region in consecutive slabs merge back into one
//! prism. The result: features that overlap neither the product nor each
//! other and that, with the part, make up the blank.

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;
use thinplan_brep::{Brep, Frame};
use thinplan_knowledge::{FeatureSelector, Knowledge, RemainingOwner, ShallowSlabs, TieBreak};
use thinplan_plan::{
    Adjacency, Constraint, ConstraintKind, FeatureOrigin, MachiningFeature, MachiningFeatureId,
    Plan, Prism, PrismFrame, ProfileLoop, Provenance, ProvenanceSource, Refusal, Region, Stage,
    StiffnessFeature, StiffnessFeatureId, StiffnessKind, WallRole,
};

mod beyond;
mod narrow;
pub mod section;
mod shank;
mod slopes;
use section::{LocalMesh, Shapes};
pub use shank::RULE_SHANK;

/// Provenance rule of remaining-material features.
pub const RULE_REMAINING: &str = "interference.remaining";
/// Provenance rule of accessibility constraints.
pub const RULE_ACCESS: &str = "interference.accessibility";
/// Provenance rule of the constraints chaining the pieces of a split feature.
pub const RULE_SPLIT: &str = "interference.split";

/// Heights closer than this are one level, mm.
const EPS_Z: f64 = 1e-6;

/// Volumes of the blank and what fills it, mm³.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeAccount {
    pub blank: f64,
    /// From the B-rep's mass properties (independent of the slicing).
    pub part: f64,
    /// All resolved features, remaining material included.
    pub features: f64,
    /// The remaining-material features alone.
    pub remaining: f64,
    /// Dropped slivers.
    pub slivers: f64,
}

impl VolumeAccount {
    /// `(part + features − blank) / blank`: zero when they make up the blank.
    pub fn relative_error(&self) -> f64 {
        (self.part + self.features - self.blank) / self.blank.max(f64::MIN_POSITIVE)
    }
}

/// The stage's result.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Resolution {
    pub features: Vec<MachiningFeature>,
    pub constraints: Vec<Constraint<MachiningFeatureId>>,
    pub refusals: Vec<Refusal>,
    pub warnings: Vec<String>,
    pub volumes: VolumeAccount,
    /// Machining order used for adjacency (a topological order of the
    /// constraints, lowest id first among the ready ones).
    pub order: Vec<MachiningFeatureId>,
    /// The blank in the set-up frame: (min, max) corners.
    pub blank: ([f64; 3], [f64; 3]),
}

impl Resolution {
    /// Replaces the plan's machining features and constraints with the
    /// resolved ones and lists the stage.
    pub fn apply_to(self, plan: &mut Plan) {
        plan.invalidate_from(Stage::Resolve);
        plan.machining_features = self.features;
        plan.machining_constraints = self.constraints;
        plan.refusals.extend(self.refusals);
        for (k, x) in [
            ("resolve.blank_min_x", self.blank.0[0]),
            ("resolve.blank_min_y", self.blank.0[1]),
            ("resolve.blank_min_z", self.blank.0[2]),
            ("resolve.blank_max_x", self.blank.1[0]),
            ("resolve.blank_max_y", self.blank.1[1]),
            ("resolve.blank_max_z", self.blank.1[2]),
        ] {
            // Full precision: later stages rebuild the product from it.
            plan.notes.insert(k.into(), format!("{x:?}"));
        }
        let v = self.volumes;
        for (k, x) in [
            ("resolve.blank_volume", v.blank),
            ("resolve.part_volume", v.part),
            ("resolve.features_volume", v.features),
            ("resolve.remaining_volume", v.remaining),
            ("resolve.sliver_volume", v.slivers),
        ] {
            plan.notes.insert(k.into(), format!("{x:.6}"));
        }
        plan.stages_done.push(Stage::Resolve);
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResolveError {
    #[error(
        "machining features have not been determined yet (stages done: {0:?}); run stage 5 first"
    )]
    NotDetermined(Vec<Stage>),
    #[error("the set-up's up axis {0} is not a direction")]
    BadUp(DVec3),
    #[error("the part has no volume to plan (empty tessellation)")]
    EmptyPart,
}

/// A stage-5 feature as a plan-view region over a height range.
struct Claim {
    from: MachiningFeatureId,
    owner: StiffnessFeatureId,
    poly: Shapes,
    bbox: [f64; 4],
    lo: f64,
    hi: f64,
    rank: (usize, f64, u32),
    rule: String,
    /// Narrow remaining material beside it may join it
    /// (`narrow_remaining_joins`).
    takes_narrow: bool,
}

/// One slab of the blank with the part's section in it.
struct Slab {
    lo: f64,
    hi: f64,
    part: Shapes,
    /// Crossed by a sloped face (subdivided by `sloped_slab_thickness`).
    sloped: bool,
}

/// A piece of a resolved feature before it gets its id.
struct Piece {
    /// Index into the claims, or `None` for remaining material.
    claim: Option<usize>,
    owner: StiffnessFeatureId,
    owner_rule: &'static str,
    /// One shape: outer contour then holes.
    region: Vec<Vec<[f64; 2]>>,
    lo: f64,
    hi: f64,
    /// Index of the top slab.
    top_slab: usize,
    bottom_slab: usize,
}

/// Runs stage 6 on a plan whose machining features have been determined.
pub fn resolve(plan: &Plan, brep: &Brep, k: &Knowledge) -> Result<Resolution, ResolveError> {
    if !plan.stages_done.contains(&Stage::Determine) {
        return Err(ResolveError::NotDetermined(plan.stages_done.clone()));
    }
    let up = plan.setup.up;
    if !(up.is_finite() && up.length() > 1e-9) {
        return Err(ResolveError::BadUp(up));
    }
    let kn = &k.interference;
    let frame = Frame::from_axis_ref(DVec3::ZERO, up.normalize(), None);
    let tess = brep.mass_tolerance();
    let mesh = thinplan_brep::tess::tessellate(brep, &tess);
    if mesh.triangles.is_empty() {
        return Err(ResolveError::EmptyPart);
    }
    let local = LocalMesh {
        positions: mesh.positions.iter().map(|p| frame.to_local(*p)).collect(),
        triangles: mesh.triangles.clone(),
    };
    let mut out = Resolution::default();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in &local.positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let blank_rect = section::rect([lo.x, lo.y], [hi.x, hi.y]);
    out.blank = ([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]);
    out.volumes.blank = (hi - lo).x * (hi - lo).y * (hi - lo).z;
    out.volumes.part = brep.volume();

    let claims = claims(plan, &frame, kn, lo.z, hi.z, &mut out.warnings);
    let slabs = slabs(
        brep,
        &local,
        &frame,
        &claims,
        lo.z,
        hi.z,
        (kn.sloped_slab_thickness, kn.shallow_slabs.as_ref()),
    );
    let mut gaps = 0;
    let slabs: Vec<Slab> = slabs
        .into_iter()
        .map(|(a, b, sloped)| {
            let (loops, g) = local.section(0.5 * (a + b));
            gaps += g;
            Slab {
                lo: a,
                hi: b,
                part: section::fill(&loops),
                sloped,
            }
        })
        .collect();
    if gaps > 0 {
        out.warnings.push(format!(
            "the part's mesh is not closed: {gaps} section loop(s) closed across a gap"
        ));
    }

    // Claims by rank: the feature needing most care first.
    let mut by_rank: Vec<usize> = (0..claims.len()).collect();
    by_rank.sort_by(|&a, &b| {
        let (ra, rb) = (&claims[a].rank, &claims[b].rank);
        ra.0.cmp(&rb.0)
            .then(ra.1.total_cmp(&rb.1))
            .then(ra.2.cmp(&rb.2))
    });
    // Per claim, its region in each slab (top-down), then merged.
    let mut claim_slabs: Vec<Vec<(usize, Shapes)>> = vec![Vec::new(); claims.len()];
    let mut remaining: Vec<(usize, Shapes)> = Vec::new();
    let mut lost: BTreeMap<(usize, usize), f64> = BTreeMap::new();
    // Remaining material joined to a claim, mm³ per claim.
    let mut joined: BTreeMap<usize, f64> = BTreeMap::new();
    let narrow_radius = k
        .tool_set(&plan.setup.tool_set)
        .filter(|_| !kn.narrow_remaining_joins.is_empty())
        .and_then(|set| {
            set.tools
                .iter()
                .map(|t| 0.5 * t.diameter)
                .min_by(f64::total_cmp)
        });
    for (si, slab) in slabs.iter().enumerate().rev() {
        let removal = section::difference(&blank_rect, &slab.part);
        let mut taken: Vec<(usize, [f64; 4], Shapes)> = Vec::new();
        for &ci in &by_rank {
            let c = &claims[ci];
            if c.lo > slab.lo + EPS_Z || c.hi < slab.hi - EPS_Z {
                continue;
            }
            let mut piece = section::intersection(&c.poly, &blank_rect);
            let near_part: Shapes = slab
                .part
                .iter()
                .filter(|s| overlaps(&bbox_of(std::slice::from_ref(*s)), &c.bbox))
                .cloned()
                .collect();
            piece = section::difference(&piece, &near_part);
            for (tj, tb, t) in &taken {
                if overlaps(tb, &c.bbox) {
                    let before = section::area(&piece);
                    piece = section::difference(&piece, t);
                    let l = before - section::area(&piece);
                    if l > kn.sliver_area {
                        *lost.entry((ci, *tj)).or_default() += l * (slab.hi - slab.lo);
                    }
                }
            }
            let piece: Shapes = piece
                .into_iter()
                .filter(|s| section::shape_area(s) > kn.sliver_area)
                .collect();
            if !piece.is_empty() {
                taken.push((ci, bbox_of(&piece), piece));
            }
        }
        // The pieces narrow remaining material may join.
        let mut joinable: Vec<(usize, [f64; 4], Shapes)> = Vec::new();
        let mut others = Vec::new();
        for t in taken {
            if claims[t.0].takes_narrow {
                joinable.push(t);
            } else {
                others.push(t);
            }
        }
        let all_taken: Shapes = joinable
            .iter()
            .chain(&others)
            .flat_map(|(_, _, s)| s.clone())
            .collect();
        let all_taken = section::fill(&all_taken.into_iter().flatten().collect::<Vec<_>>());
        let rem = section::difference(&removal, &all_taken);
        let (mut keep, drop): (Shapes, Shapes) = rem
            .into_iter()
            .partition(|s| section::shape_area(s) > kn.sliver_area);
        out.volumes.slivers += section::area(&drop) * (slab.hi - slab.lo);
        if let Some(r) = narrow_radius {
            for (ci, a) in narrow::join_narrow(&mut keep, &mut joinable, r, kn.sliver_area) {
                *joined.entry(ci).or_default() += a * (slab.hi - slab.lo);
            }
        }
        for (ci, _, piece) in joinable.into_iter().chain(others) {
            claim_slabs[ci].push((si, piece));
        }
        if !keep.is_empty() {
            remaining.push((si, keep));
        }
    }

    // Merge each claim's slab regions into prisms (top-down).
    let mut pieces: Vec<Piece> = Vec::new();
    for (ci, list) in claim_slabs.into_iter().enumerate() {
        let c = &claims[ci];
        let mut groups: Vec<(usize, usize, Shapes)> = Vec::new();
        for (si, region) in list {
            match groups.last_mut() {
                Some((_, bottom, g))
                    if *bottom == si + 1 && section::same_region(g, &region, 1e-6) =>
                {
                    *bottom = si;
                }
                _ => groups.push((si, si, region)),
            }
        }
        for (top, bottom, region) in groups {
            let mut shapes = section::pieces(region);
            sort_shapes(&mut shapes);
            for s in shapes {
                pieces.push(Piece {
                    claim: Some(ci),
                    owner: c.owner,
                    owner_rule: "",
                    region: s.into_iter().next().expect("one shape"),

                    lo: slabs[bottom].lo,
                    hi: slabs[top].hi,
                    top_slab: top,
                    bottom_slab: bottom,
                });
            }
        }
    }
    let n_claimed = pieces.len();
    // Remaining material: per slab, each connected shape gets an owner; the
    // same region with the same owner in the slab below extends the piece.
    let mut open: Vec<usize> = Vec::new();
    for (si, region) in remaining {
        let mid = 0.5 * (slabs[si].lo + slabs[si].hi);
        let mut next_open = Vec::new();
        let mut shapes = section::pieces(region);
        sort_shapes(&mut shapes);
        for s in shapes {
            let (owner, owner_rule) = remaining_owner(plan, &frame, &kn.remaining_owners, &s, mid);
            let shape = s.into_iter().next().expect("one shape");
            let extend = open.iter().copied().find(|&pi| {
                let p = &pieces[pi];
                p.owner == owner
                    && p.bottom_slab == si + 1
                    && section::same_region(&vec![p.region.clone()], &vec![shape.clone()], 1e-6)
            });
            match extend {
                Some(pi) => {
                    pieces[pi].bottom_slab = si;
                    pieces[pi].lo = slabs[si].lo;
                    next_open.push(pi);
                }
                None => {
                    pieces.push(Piece {
                        claim: None,
                        owner,
                        owner_rule,
                        region: shape,
                        lo: slabs[si].lo,
                        hi: slabs[si].hi,
                        top_slab: si,
                        bottom_slab: si,
                    });
                    next_open.push(pieces.len() - 1);
                }
            }
        }
        open = next_open;
    }
    // Remaining features ordered by owner, then top-down.
    let mut rem_idx: Vec<usize> = (n_claimed..pieces.len()).collect();
    rem_idx.sort_by(|&a, &b| {
        let (pa, pb) = (&pieces[a], &pieces[b]);
        pa.owner
            .cmp(&pb.owner)
            .then(pb.hi.total_cmp(&pa.hi))
            .then(a.cmp(&b))
    });
    let order_idx: Vec<usize> = (0..n_claimed).chain(rem_idx).collect();

    // Features with their ids.
    let mut from_claim: BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>> = BTreeMap::new();
    let mut geo: Vec<Geo> = Vec::new();
    for (new_i, &pi) in order_idx.iter().enumerate() {
        let p = &pieces[pi];
        let id = MachiningFeatureId(new_i as u32);
        let area = section::shape_area(&p.region);
        let vol = area * (p.hi - p.lo);
        out.volumes.features += vol;
        let mut origin = FeatureOrigin::default();
        let provenance = match p.claim {
            Some(ci) => {
                let c = &claims[ci];
                from_claim.entry(c.from).or_default().push(id);
                let original = plan
                    .machining_features
                    .iter()
                    .find(|f| f.id == c.from)
                    .expect("claims come from features");
                origin = original.origin.clone();
                let mut prov = original.provenance.clone();
                prov.values
                    .insert("determined_as".into(), f64::from(c.from.0));
                let losers: Vec<String> = lost
                    .iter()
                    .filter(|((a, _), _)| *a == ci)
                    .map(|((_, b), v)| format!("{v:.1} mm³ to {}", claims[*b].from))
                    .collect();
                let with = joined.get(&ci).map_or(String::new(), |v| {
                    format!(
                        ", with {v:.1} mm³ of remaining material beside it too narrow \
                         for the smallest tool"
                    )
                });
                if let Some(v) = joined.get(&ci) {
                    prov.values.insert("joined_remaining_mm3".into(), *v);
                }
                prov.note = format!(
                    "{}; resolved from {} ({}), product subtracted{}{with}",
                    prov.note,
                    c.from,
                    c.rule,
                    if losers.is_empty() {
                        String::new()
                    } else {
                        format!(
                            ", overlap kept by features needing more care: {}",
                            losers.join(", ")
                        )
                    }
                );
                prov
            }
            None => {
                out.volumes.remaining += vol;
                origin.rule = RULE_REMAINING.into();
                let mut prov = Provenance::new(ProvenanceSource::Knowledge, RULE_REMAINING)
                    .with_value("owner", f64::from(p.owner.0));
                prov.note = format!(
                    "remaining material (no stage-5 feature claims it), owned by {} ({})",
                    p.owner, p.owner_rule
                );
                prov
            }
        };
        geo.push(Geo {
            bbox: bbox_of(std::slice::from_ref(&p.region)),
            region: vec![p.region.clone()],
            lo: p.lo,
            top_slab: p.top_slab,
            bottom_slab: p.bottom_slab,
        });
        out.features.push(MachiningFeature {
            id,
            owner: p.owner,
            shape: prism(&frame, &p.region, p.lo, p.hi),
            side_adjacency: Vec::new(),
            hole_adjacency: Vec::new(),
            bottom_adjacency: Adjacency::Open,
            origin,
            access_blocked: false,
            slopes: None,
            provenance,
        });
    }
    for (ci, c) in claims.iter().enumerate() {
        if !from_claim.contains_key(&c.from) {
            let note = if lost.keys().any(|(a, _)| *a == ci) {
                "its volume is kept by features that need more care"
            } else {
                "it lies wholly in the product or outside the blank"
            };
            out.warnings.push(format!(
                "{} vanished in interference handling: {note}",
                c.from
            ));
        }
    }

    let mut graph = Graph::new(out.features.len());
    // A split feature's pieces are machined top-down.
    for (from, ids) in &from_claim {
        for w in ids.windows(2) {
            let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_SPLIT)
                .with_value("determined_as", f64::from(from.0));
            p.note = format!("pieces of {from}, top-down");
            graph.add(&mut out, w[0], w[1], ConstraintKind::Before, 0, p);
        }
    }
    redirect(plan, &from_claim, &mut graph, &mut out);
    if kn.accessibility {
        accessibility(&geo, &slabs, kn.sliver_area, &mut graph, &mut out);
    }
    if kn.shank_access {
        match k.tool_set(&plan.setup.tool_set) {
            Some(set) => shank::shank_access(
                &geo,
                &slabs,
                &set.tools,
                kn.sliver_area,
                &mut graph,
                &mut out,
            ),
            None => out.warnings.push(format!(
                "tool set `{}` is not in the knowledge: shank access not checked",
                plan.setup.tool_set
            )),
        }
    }
    blocked_from_up(&geo, &slabs, (kn.sliver_area, tess.chord), &mut out);
    out.order = graph.topological_order();
    adjacency(&mut out, &geo, &slabs, [lo.x, lo.y, hi.x, hi.y], lo.z);
    let reach = (hi - lo).length();
    // Faces are sampled up to where the largest corner radius reaches.
    let above = k.tool_set(&plan.setup.tool_set).map_or(0.0, |set| {
        set.tools
            .iter()
            .map(|t| t.corner_radius)
            .fold(0.0, f64::max)
    });
    let mut sections: slopes::SectionCache = BTreeMap::new();
    for (f, g) in geo.iter().enumerate() {
        if g.bottom_slab == g.top_slab && slabs[g.bottom_slab].sloped {
            let mf = &out.features[f];
            let slopes = slopes::edge_slopes(
                &local,
                g,
                (slabs[g.top_slab].hi, hi.z),
                (&mf.side_adjacency, &mf.hole_adjacency),
                (above, reach),
                &mut sections,
            );
            out.features[f].slopes = slopes;
        }
    }
    Ok(out)
}

/// The plan-view geometry of a resolved feature.
struct Geo {
    region: Shapes,
    bbox: [f64; 4],
    lo: f64,
    top_slab: usize,
    bottom_slab: usize,
}

fn sort_shapes(shapes: &mut [Shapes]) {
    shapes.sort_by(|a, b| {
        let (ba, bb) = (bbox_of(a), bbox_of(b));
        ba[0].total_cmp(&bb[0]).then(ba[1].total_cmp(&bb[1]))
    });
}

fn bbox_of(s: &[Vec<Vec<[f64; 2]>>]) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in s.iter().flatten().flatten() {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

fn overlaps(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] + 1e-9 && b[0] <= a[2] + 1e-9 && a[1] <= b[3] + 1e-9 && b[1] <= a[3] + 1e-9
}

/// A prism in the set-up frame from a plan-view shape (outer contour, then holes).
fn prism(frame: &Frame, shape: &[Vec<[f64; 2]>], lo: f64, hi: f64) -> Prism {
    let lp = |contour: &Vec<[f64; 2]>| ProfileLoop::polygon(contour);
    Prism {
        frame: PrismFrame {
            origin: frame.origin,
            x: frame.x,
            z: frame.z,
        },
        region: Region {
            outer: lp(&shape[0]),
            holes: shape[1..].iter().map(lp).collect(),
        },
        z_min: lo,
        z_max: hi,
    }
}

/// Points of a profile loop with arcs flattened to chords of at most a
/// sixteenth of a half-turn.
fn flatten(lp: &ProfileLoop) -> Vec<(f64, f64)> {
    let n = lp.vertices.len();
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b) = (lp.vertices[i], lp.vertices[(i + 1) % n]);
        out.push((a.x, a.y));
        if a.bulge.abs() > 1e-12 {
            let sweep = 4.0 * a.bulge.atan();
            let chord = ((b.x - a.x).powi(2) + (b.y - a.y).powi(2)).sqrt();
            let r = chord / (2.0 * (sweep / 2.0).sin()).abs();
            let (mx, my) = (0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
            let d = (r * r - chord * chord / 4.0).max(0.0).sqrt();
            // Centre to the left of a→b for a counter-clockwise arc under π.
            let (ux, uy) = ((b.x - a.x) / chord, (b.y - a.y) / chord);
            let side = if (sweep > 0.0) == (sweep.abs() < std::f64::consts::PI) {
                1.0
            } else {
                -1.0
            };
            let (cx, cy) = (mx - uy * d * side, my + ux * d * side);
            let a0 = (a.y - cy).atan2(a.x - cx);
            let steps = ((sweep.abs() / (std::f64::consts::PI / 16.0)).ceil() as usize).max(1);
            for s in 1..steps {
                let t = a0 + sweep * s as f64 / steps as f64;
                out.push((cx + r * t.cos(), cy + r * t.sin()));
            }
        }
    }
    out
}

/// Stage-5 features as plan-view claims in the set-up frame.
fn claims(
    plan: &Plan,
    frame: &Frame,
    kn: &thinplan_knowledge::InterferenceKnowledge,
    zlo: f64,
    zhi: f64,
    warnings: &mut Vec<String>,
) -> Vec<Claim> {
    let thickness = |id: StiffnessFeatureId| {
        plan.stiffness_features
            .iter()
            .find(|f| f.id == id)
            .and_then(|f| f.thickness)
            .unwrap_or(f64::INFINITY)
    };
    let mut out = Vec::new();
    for f in &plan.machining_features {
        let s = &f.shape;
        let z = s.frame.z.normalize_or_zero();
        let x = s.frame.x.normalize_or_zero();
        let y = z.cross(x);
        let pts2 = flatten(&s.region.outer);
        let along = z.dot(frame.z);
        let (poly, lo, hi) = if along.abs() > 1.0 - 1e-9 {
            let base = frame.to_local(s.frame.origin);
            let c: Vec<[f64; 2]> = pts2
                .iter()
                .map(|&(u, v)| {
                    let p = frame.to_local(s.frame.origin + x * u + y * v);
                    [p.x, p.y]
                })
                .collect();
            let (a, b) = (base.z + along * s.z_min, base.z + along * s.z_max);
            (section::fill(&[c]), a.min(b), a.max(b))
        } else {
            if along.abs() > 1e-9 {
                warnings.push(format!(
                    "{}: its access is inclined to the set-up's up; resolved by its plan-view hull",
                    f.id
                ));
            }
            let mut pts = Vec::new();
            let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
            for &(u, v) in &pts2 {
                for w in [s.z_min, s.z_max] {
                    let p = frame.to_local(s.frame.origin + x * u + y * v + z * w);
                    a = a.min(p.z);
                    b = b.max(p.z);
                    pts.push([p.x, p.y]);
                }
            }
            (section::fill(&[convex_hull(pts)]), a, b)
        };
        let (lo, hi) = (lo.max(zlo), hi.min(zhi));
        if poly.is_empty() || hi - lo <= EPS_Z {
            warnings.push(format!("{}: empty within the blank; dropped", f.id));
            continue;
        }
        let rule_rank = kn
            .keep_order
            .iter()
            .position(|r| selects(&r.select, f))
            .unwrap_or(kn.keep_order.len());
        let rule = kn
            .keep_order
            .get(rule_rank)
            .map_or("no keep rule".to_string(), |r| {
                format!("interference.{}", r.id)
            });
        let tie = match kn.tie_break {
            TieBreak::ThinnerOwner => thickness(f.owner),
            TieBreak::FirstMade => 0.0,
        };
        out.push(Claim {
            from: f.id,
            owner: f.owner,
            bbox: bbox_of(&poly),
            poly,
            lo,
            hi,
            rank: (rule_rank, tie, f.id.0),
            rule,
            takes_narrow: kn.narrow_remaining_joins.iter().any(|s| selects(s, f)),
        });
    }
    out
}

fn selects(sel: &FeatureSelector, f: &MachiningFeature) -> bool {
    match sel {
        FeatureSelector::Any => true,
        FeatureSelector::Block { block, large } => {
            f.origin.rule == format!("strategies.{block}")
                && large.is_none_or(|l| f.origin.large == Some(l))
        }
    }
}

/// Andrew's monotone chain; counter-clockwise.
fn convex_hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut lower: Vec<[f64; 2]> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<[f64; 2]> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Slab boundaries: the blank's bottom and top, every B-rep vertex height,
/// every claim's bounds; slabs crossed by sloped faces subdivided (and
/// flagged).
fn slabs(
    brep: &Brep,
    local: &LocalMesh,
    frame: &Frame,
    claims: &[Claim],
    zlo: f64,
    zhi: f64,
    (sloped_max, shallow): (f64, Option<&ShallowSlabs>),
) -> Vec<(f64, f64, bool)> {
    let mut zs: Vec<f64> = vec![zlo, zhi];
    zs.extend(brep.vertices.iter().map(|v| frame.to_local(v.point).z));
    zs.extend(claims.iter().flat_map(|c| [c.lo, c.hi]));
    zs.retain(|z| *z >= zlo - EPS_Z && *z <= zhi + EPS_Z);
    zs.sort_by(f64::total_cmp);
    let mut levels: Vec<f64> = Vec::new();
    for z in zs {
        if levels.last().is_none_or(|l| z - l > EPS_Z) {
            levels.push(z.clamp(zlo, zhi));
        }
    }
    // Height intervals of sloped triangles, with the sine of their slope
    // from horizontal.
    let mut sloped: Vec<(f64, f64, f64)> = Vec::new();
    for t in &local.triangles {
        let v = t.map(|i| local.positions[i as usize]);
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = n.length();
        if len < 1e-300 {
            continue;
        }
        let nz = (n.z / len).abs();
        if nz > 1e-7 && nz < 1.0 - 1e-7 {
            let a = v[0].z.min(v[1].z).min(v[2].z);
            let b = v[0].z.max(v[1].z).max(v[2].z);
            sloped.push((a, b, (1.0 - nz * nz).max(0.0).sqrt()));
        }
    }
    sloped.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64, bool)> = Vec::new();
    for w in levels.windows(2) {
        let (a, b) = (w[0], w[1]);
        let is_sloped = sloped
            .iter()
            .take_while(|s| s.0 < b - EPS_Z)
            .any(|s| s.1 > a + EPS_Z);
        let Some(sh) = shallow.filter(|_| is_sloped) else {
            let n = if is_sloped {
                ((b - a) / sloped_max).ceil().max(1.0) as usize
            } else {
                1
            };
            for i in 0..n {
                out.push((
                    a + (b - a) * i as f64 / n as f64,
                    a + (b - a) * (i + 1) as f64 / n as f64,
                    is_sloped,
                ));
            }
            continue;
        };
        // Bottom up: each slab as thick as the shallowest face within the
        // largest thickness above allows (the rest of the band split
        // evenly at that thickness, so no sliver is left at its top).
        let mut z = a;
        while z < b - EPS_Z {
            let reach = (z + sloped_max).min(b);
            let t = sloped
                .iter()
                .take_while(|s| s.0 < reach - EPS_Z)
                .filter(|s| s.1 > z + EPS_Z)
                .map(|s| sh.along_face * s.2)
                .fold(sloped_max, f64::min)
                .max(sh.min_thickness);
            // Never thinner than the minimum (a short band may then be up
            // to twice the local thickness).
            let n = ((b - z) / t - 1e-9)
                .ceil()
                .min(((b - z) / sh.min_thickness + 1e-9).floor())
                .max(1.0);
            let next = if n <= 1.0 { b } else { z + (b - z) / n };
            out.push((z, next, true));
            z = next;
        }
    }
    out
}

/// The owner of a remaining piece by the knowledge's list.
fn remaining_owner(
    plan: &Plan,
    frame: &Frame,
    owners: &[RemainingOwner],
    shape: &Shapes,
    z: f64,
) -> (StiffnessFeatureId, &'static str) {
    let inner = shape
        .first()
        .and_then(|s| section::interior_point(s))
        .unwrap_or([0.0, 0.0]);
    let point = frame.to_world(DVec3::new(inner[0], inner[1], z));
    let below = frame.to_world(DVec3::new(inner[0], inner[1], z - 1e9));
    for rule in owners {
        let found = match rule {
            RemainingOwner::Depression => plan
                .stiffness_features
                .iter()
                .filter(|f| !matches!(f.kind, StiffnessKind::Wall))
                .find(|f| {
                    f.shape
                        .as_ref()
                        .is_some_and(|s| prism_contains(s, point, 1e-6))
                })
                .map(|f| (f.id, "a depression holds it")),
            RemainingOwner::Web => plan
                .stiffness_features
                .iter()
                .filter(|f| f.role == Some(WallRole::Web))
                .filter(|f| {
                    // The web lies under the piece: the vertical line through
                    // it crosses the web's prism below the piece.
                    f.shape
                        .as_ref()
                        .is_some_and(|s| segment_hits_prism(s, below, point))
                })
                .max_by(|a, b| web_top(a, frame).total_cmp(&web_top(b, frame)))
                .map(|f| (f.id, "the web under it")),
            RemainingOwner::NearestWall => plan
                .stiffness_features
                .iter()
                .filter(|f| matches!(f.kind, StiffnessKind::Wall))
                .filter_map(|f| f.shape.as_ref().map(|s| (f, prism_distance(s, point))))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.id.cmp(&b.0.id)))
                .map(|(f, _)| (f.id, "the nearest wall")),
        };
        if let Some(found) = found {
            return found;
        }
    }
    (
        plan.stiffness_features
            .first()
            .map_or(StiffnessFeatureId(0), |f| f.id),
        "no owner rule applied: the first stiffness feature",
    )
}

fn web_top(f: &StiffnessFeature, frame: &Frame) -> f64 {
    f.shape.as_ref().map_or(f64::NEG_INFINITY, |s| {
        prism_corners(s)
            .iter()
            .map(|p| frame.to_local(*p).z)
            .fold(f64::NEG_INFINITY, f64::max)
    })
}

fn prism_corners(s: &Prism) -> Vec<DVec3> {
    let z = s.frame.z.normalize_or_zero();
    let x = s.frame.x.normalize_or_zero();
    let y = z.cross(x);
    flatten(&s.region.outer)
        .into_iter()
        .flat_map(|(u, v)| [s.z_min, s.z_max].map(|w| s.frame.origin + x * u + y * v + z * w))
        .collect()
}

/// Whether a world point lies in a prism (with a tolerance).
fn prism_contains(s: &Prism, p: DVec3, tol: f64) -> bool {
    let z = s.frame.z.normalize_or_zero();
    let x = s.frame.x.normalize_or_zero();
    let y = z.cross(x);
    let d = p - s.frame.origin;
    let w = d.dot(z);
    if w < s.z_min - tol || w > s.z_max + tol {
        return false;
    }
    let c: Vec<[f64; 2]> = flatten(&s.region.outer)
        .into_iter()
        .map(|(u, v)| [u, v])
        .collect();
    section::contains(&vec![vec![c]], [d.dot(x), d.dot(y)])
}

/// Whether the segment a–b passes through the prism (sampled along it at
/// the prism's own height steps: a prism is convex along its axis).
fn segment_hits_prism(s: &Prism, a: DVec3, b: DVec3) -> bool {
    let z = s.frame.z.normalize_or_zero();
    let (wa, wb) = ((a - s.frame.origin).dot(z), (b - s.frame.origin).dot(z));
    if (wb - wa).abs() < 1e-12 {
        return prism_contains(s, a, 1e-6);
    }
    // The segment is along the set-up's up; the web's prism axis is too
    // (or nearly): test at the middle of the prism's height range.
    let t = ((0.5 * (s.z_min + s.z_max)) - wa) / (wb - wa);
    (0.0..=1.0).contains(&t) && prism_contains(s, a + (b - a) * t, 1e-6)
}

/// Distance from a point to a prism's corner hull, approximated by the
/// distance to its bounding box (enough to pick the nearest wall).
fn prism_distance(s: &Prism, p: DVec3) -> f64 {
    let c = prism_corners(s);
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for q in &c {
        lo = lo.min(*q);
        hi = hi.max(*q);
    }
    (p.clamp(lo, hi) - p).length()
}

/// The machining constraints as a graph that refuses cycles.
struct Graph {
    succ: Vec<BTreeSet<usize>>,
    pred: Vec<BTreeSet<usize>>,
}

impl Graph {
    fn new(n: usize) -> Self {
        Graph {
            succ: vec![BTreeSet::new(); n],
            pred: vec![BTreeSet::new(); n],
        }
    }

    fn reaches(&self, from: usize, to: usize) -> bool {
        let mut seen = vec![false; self.succ.len()];
        let mut stack = vec![from];
        while let Some(v) = stack.pop() {
            if v == to {
                return true;
            }
            for &w in &self.succ[v] {
                if !seen[w] {
                    seen[w] = true;
                    stack.push(w);
                }
            }
        }
        false
    }

    /// Adds `a before b` unless it would close a cycle (then a refusal) or
    /// is already implied (then nothing).
    fn add(
        &mut self,
        out: &mut Resolution,
        a: MachiningFeatureId,
        b: MachiningFeatureId,
        kind: ConstraintKind,
        priority: i32,
        provenance: Provenance,
    ) -> bool {
        let (ia, ib) = (a.0 as usize, b.0 as usize);
        if ia == ib || self.succ[ia].contains(&ib) {
            return false;
        }
        if self.reaches(ib, ia) {
            let mut provenance = provenance;
            provenance.values.insert("first".into(), f64::from(a.0));
            provenance.values.insert("second".into(), f64::from(b.0));
            out.refusals.push(Refusal {
                stage: Stage::Resolve,
                rule: provenance.rule.clone(),
                reason: format!(
                    "{a} before {b} would close a cycle ({b} already comes before {a})"
                ),
                provenance,
            });
            return false;
        }
        self.succ[ia].insert(ib);
        self.pred[ib].insert(ia);
        out.constraints.push(Constraint {
            first: a,
            second: b,
            kind,
            priority,
            provenance,
        });
        true
    }

    /// Kahn's algorithm, lowest index first among the ready ones.
    fn topological_order(&self) -> Vec<MachiningFeatureId> {
        let n = self.succ.len();
        let mut indeg: Vec<usize> = self.pred.iter().map(BTreeSet::len).collect();
        let mut ready: BTreeSet<usize> = (0..n).filter(|&i| indeg[i] == 0).collect();
        let mut order = Vec::with_capacity(n);
        while let Some(v) = ready.pop_first() {
            order.push(MachiningFeatureId(v as u32));
            for &w in &self.succ[v] {
                indeg[w] -= 1;
                if indeg[w] == 0 {
                    ready.insert(w);
                }
            }
        }
        order
    }
}

/// Stage-5 constraints redirected to the resolved pieces: `A before B`
/// becomes last piece of A before first piece of B; a vanished feature is
/// bridged (its predecessors before its successors).
fn redirect(
    plan: &Plan,
    pieces: &BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>>,
    graph: &mut Graph,
    out: &mut Resolution,
) {
    let mut preds: BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>> = BTreeMap::new();
    let mut succs: BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>> = BTreeMap::new();
    for c in &plan.machining_constraints {
        preds.entry(c.second).or_default().push(c.first);
        succs.entry(c.first).or_default().push(c.second);
    }
    fn ends(
        id: MachiningFeatureId,
        pieces: &BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>>,
        next: &BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>>,
        last: bool,
        depth: usize,
    ) -> Vec<MachiningFeatureId> {
        if let Some(p) = pieces.get(&id) {
            return vec![if last {
                *p.last().expect("non-empty")
            } else {
                p[0]
            }];
        }
        if depth > 64 {
            return Vec::new();
        }
        next.get(&id)
            .into_iter()
            .flatten()
            .flat_map(|n| ends(*n, pieces, next, last, depth + 1))
            .collect()
    }
    for c in &plan.machining_constraints {
        let firsts = ends(c.first, pieces, &preds, true, 0);
        let seconds = ends(c.second, pieces, &succs, false, 0);
        for &a in &firsts {
            for &b in &seconds {
                let mut p = c.provenance.clone();
                if !(pieces.contains_key(&c.first) && pieces.contains_key(&c.second)) {
                    p.note = format!("{}; bridged over a vanished feature", p.note);
                }
                p.values
                    .insert("determined_first".into(), f64::from(c.first.0));
                p.values
                    .insert("determined_second".into(), f64::from(c.second.0));
                graph.add(out, a, b, c.kind, c.priority, p);
            }
        }
    }
}

/// Provenance rule of features the part covers from the tool-access side.
pub const RULE_BLOCKED: &str = "interference.access_blocked";

/// A feature with product above it (an undercut: a hole through a standing
/// wall, material under an overhang) cannot be reached along up in this
/// set-up: it is marked (`access_blocked` = 1 in its provenance) and a
/// refusal says why, so later stages leave it to another set-up. The
/// sections are the mesh's, each up to its `chord` off a curved face and
/// not the same chords at every height: product above that overlaps the
/// region by no more than that is the same face, not a cover.
fn blocked_from_up(geo: &[Geo], slabs: &[Slab], (sliver, chord): (f64, f64), out: &mut Resolution) {
    for (i, g) in geo.iter().enumerate() {
        let covered = slabs[g.top_slab + 1..]
            .iter()
            .map(|s| covered_area(&g.region, &s.part, sliver, chord))
            .fold(0.0, f64::max);
        if covered > sliver {
            let f = &mut out.features[i];
            f.access_blocked = true;
            f.provenance.values.insert("access_blocked".into(), 1.0);
            f.provenance.note = format!(
                "{}; the part covers {covered:.2} mm² of it from above: not reachable along up",
                f.provenance.note
            );
            let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_BLOCKED)
                .with_value("covered_area", covered)
                .with_value("first", f64::from(f.id.0))
                .with_value("second", f64::from(f.id.0));
            p.note = "needs another set-up or side access".into();
            out.refusals.push(Refusal {
                stage: Stage::Resolve,
                rule: RULE_BLOCKED.into(),
                reason: format!(
                    "{} lies under the part ({covered:.2} mm² covered from above): it cannot be \
                     machined along this set-up's up",
                    f.id
                ),
                provenance: p,
            });
        }
    }
}

/// The area of `region` the section `above` covers, less a band of
/// `chord` (the sections' own error) along its edges; 0 when no more than
/// `sliver` overlaps at all.
fn covered_area(region: &Shapes, above: &Shapes, sliver: f64, chord: f64) -> f64 {
    let over = section::intersection(region, above);
    if section::area(&over) <= sliver {
        return 0.0;
    }
    section::area(&section::offset(&over, -chord))
}

/// A feature lying on top of another (touching, overlapping in plan view)
/// blocks its tool access from above: it comes first.
fn accessibility(
    geo: &[Geo],
    slabs: &[Slab],
    sliver: f64,
    graph: &mut Graph,
    out: &mut Resolution,
) {
    // Features by their bottom slab, to find who sits on whom.
    let mut by_bottom: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, g) in geo.iter().enumerate() {
        by_bottom.entry(g.bottom_slab).or_default().push(i);
    }
    for (b, gb) in geo.iter().enumerate() {
        if gb.top_slab + 1 >= slabs.len() {
            continue;
        }
        let Some(above) = by_bottom.get(&(gb.top_slab + 1)).map(|v| v.to_vec()) else {
            continue;
        };
        for a in above {
            let ga = &geo[a];
            // Features above `b` that start exactly on its top.
            if ga.bottom_slab != gb.top_slab + 1 || !overlaps(&ga.bbox, &gb.bbox) {
                continue;
            }
            let common = section::area(&section::intersection(&ga.region, &gb.region));
            if common <= sliver {
                continue;
            }
            let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_ACCESS)
                .with_value("overlap_area", common);
            p.note = format!("MF{a} lies on MF{b} and blocks its tool access");
            graph.add(
                out,
                MachiningFeatureId(a as u32),
                MachiningFeatureId(b as u32),
                ConstraintKind::Before,
                0,
                p,
            );
        }
    }
}

/// Adjacency of every edge and of the bottom of every feature: the product
/// (the part's section beyond the edge), another feature that comes later
/// in `order` (not yet removed), or open (air, or a feature already removed).
fn adjacency(out: &mut Resolution, geo: &[Geo], slabs: &[Slab], blank: [f64; 4], zlo: f64) {
    let mut pos = vec![0usize; geo.len()];
    for (i, id) in out.order.iter().enumerate() {
        pos[id.0 as usize] = i;
    }
    let mut in_slab: Vec<Vec<usize>> = vec![Vec::new(); slabs.len()];
    for (i, g) in geo.iter().enumerate() {
        for list in &mut in_slab[g.bottom_slab..=g.top_slab] {
            list.push(i);
        }
    }
    let classify = |f: usize, q: [f64; 2], si: usize| -> Adjacency {
        let eps = 1e-9;
        if q[0] < blank[0] - eps
            || q[0] > blank[2] + eps
            || q[1] < blank[1] - eps
            || q[1] > blank[3] + eps
        {
            return Adjacency::Open;
        }
        if section::contains(&slabs[si].part, q) {
            return Adjacency::Product;
        }
        for &g in &in_slab[si] {
            if g != f {
                let b = &geo[g].bbox;
                if q[0] >= b[0]
                    && q[0] <= b[2]
                    && q[1] >= b[1]
                    && q[1] <= b[3]
                    && section::contains(&geo[g].region, q)
                {
                    return if pos[g] > pos[f] {
                        Adjacency::Feature
                    } else {
                        Adjacency::Open
                    };
                }
            }
        }
        Adjacency::Open
    };
    let worst = |a: Adjacency, b: Adjacency| match (a, b) {
        (Adjacency::Product, _) | (_, Adjacency::Product) => Adjacency::Product,
        (Adjacency::Feature, _) | (_, Adjacency::Feature) => Adjacency::Feature,
        _ => Adjacency::Open,
    };
    for (f, g) in geo.iter().enumerate() {
        let edge_adjacency = |contour: &Vec<[f64; 2]>| -> Vec<Adjacency> {
            let n = contour.len();
            (0..n)
                .map(|i| {
                    let (a, b) = (contour[i], contour[(i + 1) % n]);
                    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                    let len = (dx * dx + dy * dy).sqrt().max(1e-300);
                    // Outward: right of a counter-clockwise edge.
                    let off = 1e-3;
                    let q = [
                        0.5 * (a[0] + b[0]) + dy / len * off,
                        0.5 * (a[1] + b[1]) - dx / len * off,
                    ];
                    (g.bottom_slab..=g.top_slab)
                        .map(|si| classify(f, q, si))
                        .fold(Adjacency::Open, worst)
                })
                .collect()
        };
        let side = edge_adjacency(&g.region[0][0]);
        let holes: Vec<Vec<Adjacency>> = g.region[0][1..].iter().map(edge_adjacency).collect();
        let bottom = if g.lo <= zlo + EPS_Z || g.bottom_slab == 0 {
            Adjacency::Open
        } else {
            let below = g.bottom_slab - 1;
            let on_part = section::area(&section::intersection(&g.region, &slabs[below].part));
            if on_part > 1e-6 {
                Adjacency::Product
            } else if in_slab[below].iter().any(|&h| {
                h != f
                    && pos[h] > pos[f]
                    && overlaps(&geo[h].bbox, &g.bbox)
                    && section::area(&section::intersection(&geo[h].region, &g.region)) > 1e-6
            }) {
                Adjacency::Feature
            } else {
                Adjacency::Open
            }
        };
        let mf = &mut out.features[f];
        mf.side_adjacency = side;
        mf.hole_adjacency = holes;
        mf.bottom_adjacency = bottom;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Product above a region covers it only where it overlaps by more
        /// than the sections' chord: a band narrower than twice the chord
        /// is the same face sectioned at two heights, a wider one an
        /// overhang, covered less the chord along its edges.
        #[test]
        fn only_an_overlap_wider_than_the_chord_covers_a_region(
            width in 1e-4f64..0.5,
            chord in 1e-3f64..0.05,
        ) {
            prop_assume!((width - 2.0 * chord).abs() > 0.1 * chord);
            let region = section::rect([0.0, 0.0], [20.0, 10.0]);
            let above = section::rect([20.0 - width, 0.0], [30.0, 10.0]);
            let covered = covered_area(&region, &above, 1e-4, chord);
            if width < 2.0 * chord {
                prop_assert!(covered == 0.0, "{covered}");
            } else {
                let want = (width - 2.0 * chord) * (10.0 - 2.0 * chord);
                prop_assert!((covered - want).abs() < 1e-3 * want + 1e-9, "{covered} vs {want}");
            }
        }

    }
}
