//! Import checks of a shell read from STEP: closed (every edge used exactly
//! twice), consistently oriented (the two uses run in opposite senses), each
//! plane face's normal agreeing with its bounds, and a positive enclosed
//! volume (negative for a void). Safe repairs are made with a warning; the
//! rest is an error naming the shell, the edges and the faces by `#id`.
//!
//! The senses are read from what the builder stores: a coedge runs along its
//! edge when `forward`, and a bound with `orientation` false reverses its
//! coedges (an `ORIENTED_FACE(.F.)` reverses its bounds that way too).

use std::collections::BTreeMap;

use glam::DVec3;
use thinplan_brep::{Brep, EdgeId, FaceId, ShellId, Surface, TessTolerance};

/// Most edges or faces a message names before it only counts the rest.
const MAX_LISTED: usize = 10;

/// What the enclosed volume's sign must be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Expect {
    /// An outer shell (or a closed surface model): positive.
    Outward,
    /// A void of a `BREP_WITH_VOIDS`: its faces point into the void.
    Inward,
}

/// File names of the B-rep's pieces, for messages.
pub(crate) trait Names {
    /// `#123` of an edge (or its polygon's points).
    fn edge(&self, e: EdgeId) -> String;
    /// `#67` of a face.
    fn face(&self, f: FaceId) -> String;
}

/// One edge whose uses do not close the shell.
#[derive(Debug, Clone, PartialEq)]
enum Problem {
    Once,
    SameSense,
    Many(usize),
}

/// The edge uses of a shell: per edge, the faces using it and whether each
/// use runs along the edge (bound orientation applied). Degenerate edges
/// (a sphere's or cone's pole) bound nothing and are left out.
fn edge_uses(b: &Brep, faces: &[FaceId]) -> BTreeMap<EdgeId, Vec<(FaceId, bool)>> {
    let mut uses: BTreeMap<EdgeId, Vec<(FaceId, bool)>> = BTreeMap::new();
    for &f in faces {
        for &l in &b.faces[f].loops {
            let lp = &b.loops[l];
            for ce in &lp.coedges {
                uses.entry(ce.edge)
                    .or_default()
                    .push((f, ce.forward == lp.orientation));
            }
        }
    }
    uses.retain(|&e, _| !is_degenerate(b, e));
    uses
}

/// A closed edge whose curve stays at its vertex: a pole, not a boundary.
fn is_degenerate(b: &Brep, e: EdgeId) -> bool {
    let edge = &b.edges[e];
    if edge.start != edge.end {
        return false;
    }
    let p = b.vertices[edge.start].point;
    let (t0, t1) = b.edge_param_range(e);
    let tol = 1e-9 * (1.0 + p.abs().max_element());
    (1..4).all(|k| {
        let q = edge.curve.point(t0 + (t1 - t0) * k as f64 / 4.0);
        // A curve that cannot be evaluated there is not a boundary either.
        !q.is_finite() || q.distance(p) <= tol
    })
}

fn problems(uses: &BTreeMap<EdgeId, Vec<(FaceId, bool)>>) -> Vec<(EdgeId, Problem)> {
    let mut out = Vec::new();
    for (&e, u) in uses {
        match u.as_slice() {
            [_] => out.push((e, Problem::Once)),
            [(_, a), (_, b)] if a == b => out.push((e, Problem::SameSense)),
            [_, _] => {}
            many => out.push((e, Problem::Many(many.len()))),
        }
    }
    out
}

/// Faces all of whose uses of edges shared with another face run in the
/// same sense as that face's: turned over against every neighbour.
fn flipped_faces(uses: &BTreeMap<EdgeId, Vec<(FaceId, bool)>>) -> Vec<FaceId> {
    // Per face: (shared edges in conflict, shared edges).
    let mut tally: BTreeMap<FaceId, (usize, usize)> = BTreeMap::new();
    for u in uses.values() {
        if let [(fa, a), (fb, b)] = u.as_slice() {
            if fa == fb {
                continue; // a seam
            }
            for f in [fa, fb] {
                let t = tally.entry(*f).or_default();
                t.1 += 1;
                t.0 += usize::from(a == b);
            }
        }
    }
    tally
        .into_iter()
        .filter(|(_, (bad, all))| *bad > 0 && bad == all)
        .map(|(f, _)| f)
        .collect()
}

fn list<T>(items: &[T], show: impl Fn(&T) -> String) -> String {
    let mut s: Vec<String> = items.iter().take(MAX_LISTED).map(show).collect();
    if items.len() > MAX_LISTED {
        s.push(format!("and {} more", items.len() - MAX_LISTED));
    }
    s.join(", ")
}

fn describe(
    names: &dyn Names,
    uses: &BTreeMap<EdgeId, Vec<(FaceId, bool)>>,
    probs: &[(EdgeId, Problem)],
    flipped: &[FaceId],
) -> String {
    let edges = list(probs, |(e, p)| {
        let name = names.edge(*e);
        match p {
            Problem::Once => format!("edge {name} used once (a face is missing)"),
            Problem::SameSense => {
                let faces = &uses[e];
                // Name the face turned over against all its neighbours when
                // there is one; else both faces.
                let who = faces
                    .iter()
                    .map(|(f, _)| *f)
                    .find(|f| flipped.contains(f))
                    .map(|f| format!("face {} is flipped", names.face(f)))
                    .unwrap_or_else(|| {
                        format!(
                            "faces {} and {} disagree",
                            names.face(faces[0].0),
                            names.face(faces[1].0)
                        )
                    });
                format!("edge {name} used twice in the same sense ({who})")
            }
            Problem::Many(n) => {
                format!("edge {name} used {n} times (a face is listed twice, or the solid is not manifold)")
            }
        }
    });
    let n = probs.len();
    format!(
        "{n} edge{} not shared by exactly two faces in opposite senses: {edges}",
        if n == 1 { " is" } else { "s are" }
    )
}

/// Newell's vector of a face's bounds (bound orientation applied): along the
/// normal its bounds imply, as long as the face's area.
fn bounds_normal(b: &Brep, f: FaceId, tol: &TessTolerance) -> DVec3 {
    let mut n = DVec3::ZERO;
    for &l in &b.faces[f].loops {
        let pts = b.loop_polyline(l, tol);
        if pts.len() < 3 {
            continue;
        }
        let o = pts[0];
        for i in 1..pts.len() - 1 {
            n += (pts[i] - o).cross(pts[i + 1] - o);
        }
    }
    0.5 * n
}

fn flip_bounds(b: &mut Brep, f: FaceId) {
    for l in b.faces[f].loops.clone() {
        b.loops[l].orientation = !b.loops[l].orientation;
    }
}

/// An estimate of the work [`check_shell`] does: edge uses plus, for the
/// volume, the surfaces' evaluation cost (B-spline nets by their degrees).
pub(crate) fn work(b: &Brep, shell: ShellId) -> u64 {
    let mut w = 0u64;
    for &f in &b.shells[shell].faces {
        let face = &b.faces[f];
        for &l in &face.loops {
            w = w.saturating_add(b.loops[l].coedges.len() as u64 * 8);
        }
        w = w.saturating_add(match &face.surface {
            Surface::BSpline {
                u_degree,
                v_degree,
                control_points,
                ..
            } => {
                let n: usize = control_points.iter().map(Vec::len).sum();
                (n as u64)
                    .saturating_mul((*u_degree as u64 + 1) * (*v_degree as u64 + 1))
                    .saturating_mul(4)
            }
            _ => 64,
        });
    }
    w
}

/// Checks (and where safe repairs) one shell. `Ok` gives the warnings for
/// the repairs made; `Err` the reason the shell is not a closed solid.
pub(crate) fn check_shell(
    b: &mut Brep,
    shell: ShellId,
    expect: Expect,
    names: &dyn Names,
) -> Result<Vec<String>, String> {
    let faces = b.shells[shell].faces.clone();
    let mut warnings = Vec::new();
    if faces.is_empty() {
        return Err("the shell has no face".into());
    }

    // 1. Closed and consistently oriented.
    let mut uses = edge_uses(b, &faces);
    let probs = problems(&uses);
    if !probs.is_empty() {
        let flipped = flipped_faces(&uses);
        let only_senses = probs.iter().all(|(_, p)| *p == Problem::SameSense);
        // Turning over a plane face is safe when that makes every edge
        // agree: its own normal (step 2) then says whether the file's
        // `same_sense` or its bounds were wrong. A curved face's normal
        // cannot be checked that way, so it stays an error.
        let planar = flipped
            .iter()
            .all(|&f| matches!(b.faces[f].surface, Surface::Plane { .. }));
        if only_senses && !flipped.is_empty() && planar {
            for &f in &flipped {
                flip_bounds(b, f);
            }
            let after = edge_uses(b, &faces);
            if problems(&after).is_empty() {
                warnings.push(format!(
                    "face{} {} ran against all {} neighbours; turned over",
                    if flipped.len() == 1 { "" } else { "s" },
                    list(&flipped, |f| names.face(*f)),
                    if flipped.len() == 1 { "its" } else { "their" },
                ));
                uses = after;
            } else {
                for &f in &flipped {
                    flip_bounds(b, f);
                }
                return Err(describe(names, &uses, &probs, &flipped));
            }
        } else {
            return Err(describe(names, &uses, &probs, &flipped));
        }
    }
    drop(uses);

    // 2. Each plane face's normal agrees with its bounds (counter-clockwise
    // seen from outside). The bounds agree with one another now, so the
    // faces that disagree with most are the ones whose `same_sense` is wrong.
    let diag = {
        let bb = b.rough_bbox();
        let d = bb.extent().length();
        if d.is_finite() && d > 0.0 {
            d
        } else {
            1.0
        }
    };
    let mut tol = TessTolerance::relative(diag, 1e-3);
    tol.angle = 0.35;
    let mut agree = Vec::new();
    let mut disagree = Vec::new();
    for &f in &faces {
        let Surface::Plane { frame } = &b.faces[f].surface else {
            continue;
        };
        let n = if b.faces[f].same_sense {
            frame.z
        } else {
            -frame.z
        };
        let nb = bounds_normal(b, f, &tol);
        let area = nb.length();
        // Slivers and faces whose bounds cancel say nothing.
        if !(area.is_finite() && area > 1e-9 * diag * diag) {
            continue;
        }
        let d = nb.dot(n) / area;
        if d > 0.5 {
            agree.push(f);
        } else if d < -0.5 {
            disagree.push(f);
        }
    }
    // A clear majority decides; an even split is an error, not a guess.
    let (major, minor) = if agree.len() >= disagree.len() {
        (&agree, &disagree)
    } else {
        (&disagree, &agree)
    };
    if !disagree.is_empty() && minor.len() * 3 >= major.len() {
        return Err(format!(
            "plane faces disagree on which side is outside: {} point with their bounds, {} against ({})",
            agree.len(),
            disagree.len(),
            list(&disagree, |f| names.face(*f)),
        ));
    }
    if disagree.len() > agree.len() {
        // Bounds clockwise about the normals nearly everywhere: the
        // exporter's convention is reversed; the normals decide (step 3).
        for &f in &faces {
            flip_bounds(b, f);
        }
        warnings.push("the faces' bounds ran clockwise about their normals; reversed".into());
    }
    if !minor.is_empty() {
        for &f in minor {
            b.faces[f].same_sense = !b.faces[f].same_sense;
        }
        let one = minor.len() == 1;
        warnings.push(format!(
            "face{} {} pointed against {} bounds and {} neighbours (ADVANCED_FACE same_sense); turned",
            if one { "" } else { "s" },
            list(minor, |f| names.face(*f)),
            if one { "its" } else { "their" },
            if one { "its" } else { "their" },
        ));
    }

    // 3. The enclosed volume's sign. Faces that cannot be tessellated leave
    // the volume unknown; the check is skipped rather than guessed.
    let mut volume = 0.0;
    let mut r = None;
    for &f in &faces {
        let Ok(mesh) = thinplan_brep::tessellate_face(b, f, &tol) else {
            return Ok(warnings);
        };
        for t in &mesh.triangles {
            let [p, q, s] = t.map(|i| mesh.positions[i as usize]);
            let o = *r.get_or_insert(p);
            volume += (p - o).dot((q - o).cross(s - o)) / 6.0;
        }
    }
    if !volume.is_finite() || volume.abs() <= 1e-12 * diag * diag * diag {
        return Err(format!("the shell encloses no volume ({volume:e} mm³)"));
    }
    let want_positive = expect == Expect::Outward;
    if (volume > 0.0) != want_positive {
        for &f in &faces {
            flip_bounds(b, f);
            b.faces[f].same_sense = !b.faces[f].same_sense;
        }
        warnings.push(format!(
            "the shell's faces pointed {} (volume {:.6e} mm³); all turned over",
            if want_positive {
                "inwards"
            } else {
                "outwards, out of its void"
            },
            volume
        ));
    }
    Ok(warnings)
}
