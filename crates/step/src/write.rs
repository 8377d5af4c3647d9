//! A STEP AP214 (ISO 10303-21, `AUTOMOTIVE_DESIGN`) writer for a [`Brep`].
//!
//! [`write_step`] gives one part: the product / shape-definition boilerplate,
//! a geometric context in millimetres and radians with an uncertainty, and
//! one `ADVANCED_BREP_SHAPE_REPRESENTATION` holding a `MANIFOLD_SOLID_BREP`
//! (or `BREP_WITH_VOIDS`) per solid. Shells that no solid holds go into a
//! `SHELL_BASED_SURFACE_MODEL` in a related
//! `MANIFOLD_SURFACE_SHAPE_REPRESENTATION`; faces that no shell holds are
//! not written.
//!
//! Reading the output back with [`crate::read_step_bytes`] gives the same
//! B-rep up to the order of its vertices and edges (the reader numbers them
//! in the order the topology first uses them): same solids, shells, faces in
//! order with their names, surfaces, loops, coedges, curves and points. Reals
//! are printed with the shortest representation that reads back to the same
//! `f64`, so the geometry is bit-for-bit the same except for the frames and
//! directions the reader re-normalises. Two exceptions, both documented on
//! the items concerned: void shells (their loops come back with the bound
//! orientation flag flipped, see [`write_step`]) and [`Surface::Other`]
//! faces, which carry no geometry.
//!
//! The output is deterministic: the same B-rep and name give the same bytes
//! (entity ids in traversal order, a fixed timestamp, shared points and
//! directions deduplicated in first-use order).

use std::collections::HashMap;
use std::fmt::Write as _;

use glam::DVec3;
use thinplan_brep::{Brep, Curve, Face, FaceId, Frame, LoopId, ShellId, Surface};

/// The timestamp written in `FILE_NAME`: fixed, so output is deterministic.
pub const TIMESTAMP: &str = "2000-01-01T00:00:00";

/// The length uncertainty declared in the context, mm.
pub const UNCERTAINTY_MM: f64 = 1e-6;

/// Writes `brep` as a STEP AP214 file for a part called `name`.
///
/// Conventions (ISO 10303-42):
/// * A face is `ADVANCED_FACE(name, bounds, surface, same_sense)`, its loops
///   `FACE_OUTER_BOUND` / `FACE_BOUND` with [`thinplan_brep::Loop::orientation`],
///   coedges `ORIENTED_EDGE`s of shared `EDGE_CURVE`s.
/// * A solid with void shells is a `BREP_WITH_VOIDS` whose voids are
///   `ORIENTED_CLOSED_SHELL(.F.)` of closed shells holding the void's faces
///   reversed (bounds and `same_sense` flipped), as the standard asks: in the
///   B-rep the void's faces point into the void, away from the material.
///   The reader turns an oriented shell's faces over (bounds and
///   `same_sense`), so a void reads back as it was.
/// * [`Surface::Other`] (a kind the reader kept by name only) has no geometry
///   to write: the face is written on a plane through its boundary (Newell's
///   normal of its first loop) and a comment in the file says so.
/// * A [`Curve::Polyline`] with fewer than two points is written through its
///   edge's vertices. Non-finite reals are written as `0.`.
pub fn write_step(brep: &Brep, name: &str) -> String {
    let mut w = Writer::new(brep);
    let ctx = w.boilerplate(name);
    w.ctx = ctx.context;

    let in_solid: Vec<bool> = {
        let mut v = vec![false; brep.shells.len()];
        for s in &brep.solids {
            for &sh in &s.shells {
                if let Some(x) = v.get_mut(sh) {
                    *x = true;
                }
            }
        }
        v
    };

    let mut items = Vec::new();
    for solid in &brep.solids {
        let Some((&outer, voids)) = solid.shells.split_first() else {
            continue;
        };
        let outer_id = w.shell(outer, "CLOSED_SHELL", false);
        let id = if voids.is_empty() {
            w.add(format!(
                "MANIFOLD_SOLID_BREP({},#{outer_id})",
                string(&solid.name)
            ))
        } else {
            let mut refs = Vec::new();
            for &v in voids {
                let cs = w.shell(v, "CLOSED_SHELL", true);
                refs.push(w.add(format!("ORIENTED_CLOSED_SHELL('',*,#{cs},.F.)")));
            }
            w.add(format!(
                "BREP_WITH_VOIDS({},#{outer_id},{})",
                string(&solid.name),
                ref_list(&refs)
            ))
        };
        items.push(id);
    }
    w.set(
        ctx.absr,
        format!(
            "ADVANCED_BREP_SHAPE_REPRESENTATION({},{},#{})",
            string(name),
            ref_list(&items),
            ctx.context
        ),
    );

    // Shells no solid holds: a surface model in a related representation.
    let loose: Vec<ShellId> = (0..brep.shells.len()).filter(|&s| !in_solid[s]).collect();
    if !loose.is_empty() {
        let mut shells = Vec::new();
        for s in loose {
            let kind = if brep.shells[s].closed {
                "CLOSED_SHELL"
            } else {
                "OPEN_SHELL"
            };
            shells.push(w.shell(s, kind, false));
        }
        let model = w.add(format!(
            "SHELL_BASED_SURFACE_MODEL('',{})",
            ref_list(&shells)
        ));
        let rep = w.add(format!(
            "MANIFOLD_SURFACE_SHAPE_REPRESENTATION({},(#{model}),#{})",
            string(name),
            ctx.context
        ));
        w.add(format!(
            "SHAPE_REPRESENTATION_RELATIONSHIP('','',#{},#{rep})",
            ctx.absr
        ));
    }
    w.finish(name)
}

/// Ids of the boilerplate entities the body refers to.
struct Boiler {
    absr: u64,
    context: u64,
}

struct Writer<'b> {
    brep: &'b Brep,
    /// Entity bodies by id - 1 (a reserved id holds an empty string until set).
    entities: Vec<String>,
    /// Comments written just before an entity.
    notes: Vec<(u64, String)>,
    ctx: u64,
    points: HashMap<[u64; 3], u64>,
    dirs: HashMap<[u64; 3], u64>,
    vertices: Vec<Option<u64>>,
    edges: Vec<Option<u64>>,
    loops: Vec<Option<u64>>,
    /// Faces as given (index 0) and reversed (index 1).
    faces: [Vec<Option<u64>>; 2],
}

impl<'b> Writer<'b> {
    fn new(brep: &'b Brep) -> Self {
        Writer {
            brep,
            entities: Vec::new(),
            notes: Vec::new(),
            ctx: 0,
            points: HashMap::new(),
            dirs: HashMap::new(),
            vertices: vec![None; brep.vertices.len()],
            edges: vec![None; brep.edges.len()],
            loops: vec![None; brep.loops.len()],
            faces: [vec![None; brep.faces.len()], vec![None; brep.faces.len()]],
        }
    }

    fn add(&mut self, body: String) -> u64 {
        self.entities.push(body);
        self.entities.len() as u64
    }

    fn reserve(&mut self) -> u64 {
        self.add(String::new())
    }

    fn set(&mut self, id: u64, body: String) {
        self.entities[(id - 1) as usize] = body;
    }

    fn boilerplate(&mut self, name: &str) -> Boiler {
        let n = string(name);
        let app = self.add(
            "APPLICATION_CONTEXT('core data for automotive mechanical design processes')".into(),
        );
        self.add(format!(
            "APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{app})"
        ));
        let pc = self.add(format!("PRODUCT_CONTEXT('',#{app},'mechanical')"));
        let product = self.add(format!("PRODUCT({n},{n},'',(#{pc}))"));
        self.add(format!(
            "PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#{product}))"
        ));
        let pdf = self.add(format!("PRODUCT_DEFINITION_FORMATION('','',#{product})"));
        let pdc = self.add(format!(
            "PRODUCT_DEFINITION_CONTEXT('part definition',#{app},'design')"
        ));
        let pd = self.add(format!("PRODUCT_DEFINITION('design','',#{pdf},#{pdc})"));
        let pds = self.add(format!("PRODUCT_DEFINITION_SHAPE('','',#{pd})"));
        let absr = self.reserve();
        self.add(format!("SHAPE_DEFINITION_REPRESENTATION(#{pds},#{absr})"));
        let mm = self.add("( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) )".into());
        let rad = self.add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )".into());
        let sr = self.add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )".into());
        let unc = self.add(format!(
            "UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE({}),#{mm},'distance_accuracy_value','confusion accuracy')",
            real(UNCERTAINTY_MM)
        ));
        let context = self.add(format!(
            "( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{unc})) \
             GLOBAL_UNIT_ASSIGNED_CONTEXT((#{mm},#{rad},#{sr})) \
             REPRESENTATION_CONTEXT('Context #1','3D Context with UNIT and UNCERTAINTY') )"
        ));
        Boiler { absr, context }
    }

    fn finish(self, name: &str) -> String {
        let mut out = String::new();
        out.push_str("ISO-10303-21;\nHEADER;\n");
        out.push_str("FILE_DESCRIPTION(('thinplan B-rep'),'2;1');\n");
        let _ = writeln!(
            out,
            "FILE_NAME({},'{TIMESTAMP}',(''),(''),'thinplan','thinplan','');",
            string(name)
        );
        out.push_str("FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\n");
        out.push_str("ENDSEC;\nDATA;\n");
        let mut notes = self.notes.iter().peekable();
        for (i, body) in self.entities.iter().enumerate() {
            let id = i as u64 + 1;
            while let Some((_, text)) = notes.next_if(|(at, _)| *at == id) {
                let _ = writeln!(out, "/* {} */", text.replace("*/", "* /"));
            }
            let _ = writeln!(out, "#{id}={body};");
        }
        out.push_str("ENDSEC;\nEND-ISO-10303-21;\n");
        out
    }

    // ------------------------------------------------------------ geometry

    fn point(&mut self, p: DVec3) -> u64 {
        let key = bits(p);
        if let Some(&id) = self.points.get(&key) {
            return id;
        }
        let id = self.add(format!("CARTESIAN_POINT('',{})", coords(p)));
        self.points.insert(key, id);
        id
    }

    fn direction(&mut self, d: DVec3) -> u64 {
        let d = if d.is_finite() && d.length_squared() > 1e-30 {
            d
        } else {
            DVec3::Z
        };
        let key = bits(d);
        if let Some(&id) = self.dirs.get(&key) {
            return id;
        }
        let id = self.add(format!("DIRECTION('',{})", coords(d)));
        self.dirs.insert(key, id);
        id
    }

    fn placement(&mut self, f: &Frame) -> u64 {
        let o = self.point(f.origin);
        let z = self.direction(f.z);
        let x = self.direction(f.x);
        self.add(format!("AXIS2_PLACEMENT_3D('',#{o},#{z},#{x})"))
    }

    fn vector(&mut self, v: DVec3) -> u64 {
        let m = v.length();
        let (d, m) = if m.is_finite() && m > 0.0 {
            (v / m, m)
        } else {
            (DVec3::Z, 0.0)
        };
        let d = self.direction(d);
        self.add(format!("VECTOR('',#{d},{})", real(m)))
    }

    fn points(&mut self, ps: &[DVec3]) -> String {
        let ids: Vec<u64> = ps.iter().map(|&p| self.point(p)).collect();
        ref_list(&ids)
    }

    /// `ends`: the edge's vertex points, for a polyline with too few points.
    fn curve(&mut self, c: &Curve, ends: [DVec3; 2]) -> u64 {
        match c {
            Curve::Line { origin, dir } => {
                let p = self.point(*origin);
                let d = self.direction(*dir);
                let v = self.add(format!("VECTOR('',#{d},1.)"));
                self.add(format!("LINE('',#{p},#{v})"))
            }
            Curve::Circle { frame, radius } => {
                let a = self.placement(frame);
                self.add(format!("CIRCLE('',#{a},{})", real(*radius)))
            }
            Curve::Ellipse {
                frame,
                semi_axis_1,
                semi_axis_2,
            } => {
                let a = self.placement(frame);
                self.add(format!(
                    "ELLIPSE('',#{a},{},{})",
                    real(*semi_axis_1),
                    real(*semi_axis_2)
                ))
            }
            Curve::BSpline {
                degree,
                control_points,
                knots,
                weights,
            } => {
                let cps = self.points(control_points);
                let closed = logical(
                    control_points.len() > 1 && control_points.first() == control_points.last(),
                );
                let (mults, ks) = compress_knots(knots);
                let k = format!("{},{},.UNSPECIFIED.", int_list(&mults), real_list(&ks));
                if weights.is_empty() {
                    self.add(format!(
                        "B_SPLINE_CURVE_WITH_KNOTS('',{degree},{cps},.UNSPECIFIED.,{closed},.F.,{k})"
                    ))
                } else {
                    self.add(format!(
                        "( BOUNDED_CURVE() B_SPLINE_CURVE({degree},{cps},.UNSPECIFIED.,{closed},.F.) \
                         B_SPLINE_CURVE_WITH_KNOTS({k}) CURVE() GEOMETRIC_REPRESENTATION_ITEM() \
                         RATIONAL_B_SPLINE_CURVE({}) REPRESENTATION_ITEM('') )",
                        real_list(weights)
                    ))
                }
            }
            Curve::Polyline { points } => {
                let ps = if points.len() >= 2 {
                    self.points(points)
                } else {
                    self.points(&ends)
                };
                self.add(format!("POLYLINE('',{ps})"))
            }
        }
    }

    fn surface(&mut self, face: &Face, fid: FaceId) -> (u64, Option<String>) {
        let id = match &face.surface {
            Surface::Plane { frame } => {
                let a = self.placement(frame);
                self.add(format!("PLANE('',#{a})"))
            }
            Surface::Cylinder { frame, radius } => {
                let a = self.placement(frame);
                self.add(format!("CYLINDRICAL_SURFACE('',#{a},{})", real(*radius)))
            }
            Surface::Cone {
                frame,
                radius,
                semi_angle,
            } => {
                let a = self.placement(frame);
                self.add(format!(
                    "CONICAL_SURFACE('',#{a},{},{})",
                    real(*radius),
                    real(*semi_angle)
                ))
            }
            Surface::Sphere { frame, radius } => {
                let a = self.placement(frame);
                self.add(format!("SPHERICAL_SURFACE('',#{a},{})", real(*radius)))
            }
            Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            } => {
                let a = self.placement(frame);
                self.add(format!(
                    "TOROIDAL_SURFACE('',#{a},{},{})",
                    real(*major_radius),
                    real(*minor_radius)
                ))
            }
            Surface::BSpline {
                u_degree,
                v_degree,
                control_points,
                u_knots,
                v_knots,
                weights,
            } => {
                let rows: Vec<String> = control_points.iter().map(|r| self.points(r)).collect();
                let cps = format!("({})", rows.join(","));
                let (um, uk) = compress_knots(u_knots);
                let (vm, vk) = compress_knots(v_knots);
                let k = format!(
                    "{},{},{},{},.UNSPECIFIED.",
                    int_list(&um),
                    int_list(&vm),
                    real_list(&uk),
                    real_list(&vk)
                );
                let base = format!("{u_degree},{v_degree},{cps},.UNSPECIFIED.,.F.,.F.,.F.");
                if weights.is_empty() {
                    self.add(format!("B_SPLINE_SURFACE_WITH_KNOTS('',{base},{k})"))
                } else {
                    let w: Vec<String> = weights.iter().map(|r| real_list(r)).collect();
                    self.add(format!(
                        "( BOUNDED_SURFACE() B_SPLINE_SURFACE({base}) B_SPLINE_SURFACE_WITH_KNOTS({k}) \
                         GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_SURFACE(({})) \
                         REPRESENTATION_ITEM('') SURFACE() )",
                        w.join(",")
                    ))
                }
            }
            Surface::Extrusion { curve, dir } => {
                let c = self.curve(curve, [DVec3::ZERO; 2]);
                let v = self.vector(*dir);
                self.add(format!("SURFACE_OF_LINEAR_EXTRUSION('',#{c},#{v})"))
            }
            Surface::Revolution {
                curve,
                axis_origin,
                axis_dir,
            } => {
                let c = self.curve(curve, [DVec3::ZERO; 2]);
                let o = self.point(*axis_origin);
                let d = self.direction(*axis_dir);
                let ax = self.add(format!("AXIS1_PLACEMENT('',#{o},#{d})"));
                self.add(format!("SURFACE_OF_REVOLUTION('',#{c},#{ax})"))
            }
            Surface::Other { kind } => {
                let frame = self.fitted_plane(face);
                let a = self.placement(&frame);
                let id = self.add(format!("PLANE('',#{a})"));
                return (
                    id,
                    Some(format!(
                        "face {fid}: surface kind {kind} has no geometry; a plane through its boundary is written instead"
                    )),
                );
            }
        };
        (id, None)
    }

    /// A plane through the face's first loop (Newell's normal), for faces
    /// whose surface has no geometry.
    fn fitted_plane(&self, face: &Face) -> Frame {
        let b = self.brep;
        let pts: Vec<DVec3> = face
            .loops
            .first()
            .and_then(|&l| b.loops.get(l))
            .map(|lp| {
                let mut v: Vec<DVec3> = lp
                    .coedges
                    .iter()
                    .filter_map(|&c| b.vertices.get(b.coedge_start(c)).map(|v| v.point))
                    .collect();
                if let Some(p) = lp.vertex.and_then(|v| b.vertices.get(v)) {
                    v.push(p.point);
                }
                v
            })
            .unwrap_or_default();
        let mut n = DVec3::ZERO;
        let mut c = DVec3::ZERO;
        for (i, p) in pts.iter().enumerate() {
            let q = pts[(i + 1) % pts.len()];
            n += DVec3::new(
                (p.y - q.y) * (p.z + q.z),
                (p.z - q.z) * (p.x + q.x),
                (p.x - q.x) * (p.y + q.y),
            );
            c += *p;
        }
        if !pts.is_empty() {
            c /= pts.len() as f64;
        }
        Frame::from_axis_ref(c, n, None)
    }

    // ------------------------------------------------------------ topology

    fn vertex(&mut self, v: usize) -> u64 {
        if let Some(id) = self.vertices[v] {
            return id;
        }
        let p = self.point(self.brep.vertices[v].point);
        let id = self.add(format!("VERTEX_POINT('',#{p})"));
        self.vertices[v] = Some(id);
        id
    }

    fn edge(&mut self, e: usize) -> u64 {
        if let Some(id) = self.edges[e] {
            return id;
        }
        let b = self.brep;
        let edge = &b.edges[e];
        let vs = self.vertex(edge.start);
        let ve = self.vertex(edge.end);
        let ends = [b.vertices[edge.start].point, b.vertices[edge.end].point];
        let c = self.curve(&edge.curve, ends);
        let id = self.add(format!(
            "EDGE_CURVE('',#{vs},#{ve},#{c},{})",
            logical(edge.same_sense)
        ));
        self.edges[e] = Some(id);
        id
    }

    fn edge_loop(&mut self, l: LoopId) -> u64 {
        if let Some(id) = self.loops[l] {
            return id;
        }
        let lp = &self.brep.loops[l];
        let id = if lp.coedges.is_empty() {
            let v = lp.vertex.map(|v| self.vertex(v));
            match v {
                Some(v) => self.add(format!("VERTEX_LOOP('',#{v})")),
                None => self.add("EDGE_LOOP('',())".into()),
            }
        } else {
            let mut oes = Vec::with_capacity(lp.coedges.len());
            for ce in &lp.coedges {
                let e = self.edge(ce.edge);
                oes.push(self.add(format!(
                    "ORIENTED_EDGE('',*,*,#{e},{})",
                    logical(ce.forward)
                )));
            }
            self.add(format!("EDGE_LOOP('',{})", ref_list(&oes)))
        };
        self.loops[l] = Some(id);
        id
    }

    /// An `ADVANCED_FACE`; `reversed` writes the topologically reversed face
    /// (every bound's orientation and `same_sense` flipped).
    fn face(&mut self, f: FaceId, reversed: bool) -> u64 {
        let slot = usize::from(reversed);
        if let Some(id) = self.faces[slot][f] {
            return id;
        }
        let face = &self.brep.faces[f];
        let mut bounds = Vec::with_capacity(face.loops.len());
        for &l in &face.loops {
            let lp = &self.brep.loops[l];
            let kind = if lp.outer {
                "FACE_OUTER_BOUND"
            } else {
                "FACE_BOUND"
            };
            let orientation = lp.orientation ^ reversed;
            let el = self.edge_loop(l);
            bounds.push(self.add(format!("{kind}('',#{el},{})", logical(orientation))));
        }
        let (s, note) = self.surface(face, f);
        let id = self.add(format!(
            "ADVANCED_FACE({},{},#{s},{})",
            string(&face.name),
            ref_list(&bounds),
            logical(face.same_sense ^ reversed)
        ));
        if let Some(n) = note {
            self.notes.push((id, n));
        }
        self.faces[slot][f] = Some(id);
        id
    }

    fn shell(&mut self, s: ShellId, kind: &str, reversed: bool) -> u64 {
        let faces: Vec<u64> = self.brep.shells[s]
            .faces
            .iter()
            .map(|&f| self.face(f, reversed))
            .collect();
        self.add(format!("{kind}('',{})", ref_list(&faces)))
    }
}

// ---------------------------------------------------------------- printing

fn bits(p: DVec3) -> [u64; 3] {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

/// A STEP real that reads back to the same `f64`: Rust's shortest round-trip
/// form with the exponent marker as `E` and a decimal point always present
/// (`1.`, `0.25`, `1.E-7`, `-2.5E20`). Non-finite values print as `0.`.
pub fn real(x: f64) -> String {
    if !x.is_finite() {
        return "0.".into();
    }
    let s = format!("{x:?}");
    let (mant, exp) = match s.split_once(['e', 'E']) {
        Some((m, e)) => (m, Some(e)),
        None => (s.as_str(), None),
    };
    let mut m = mant.to_string();
    if !m.contains('.') {
        m.push('.');
    } else if let Some(stripped) = m.strip_suffix(".0") {
        m = format!("{stripped}.");
    }
    match exp {
        Some(e) => format!("{m}E{e}"),
        None => m,
    }
}

/// A STEP string literal: quotes doubled, backslashes escaped, anything
/// outside printable ASCII as `\X2\…\X0\` (UTF-16) or `\X4\…\X0\`.
pub fn string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('\'');
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => out.push_str("''"),
            '\\' => out.push_str("\\\\"),
            ' '..='~' => out.push(c),
            _ => {
                // A run of non-ASCII characters in one escape.
                let mut run = vec![c];
                while let Some(&n) = chars.peek() {
                    if (' '..='~').contains(&n) {
                        break;
                    }
                    run.push(n);
                    chars.next();
                }
                if run.iter().all(|c| (*c as u32) <= 0xFFFF) {
                    out.push_str("\\X2\\");
                    for c in run {
                        let _ = write!(out, "{:04X}", c as u32);
                    }
                } else {
                    out.push_str("\\X4\\");
                    for c in run {
                        let _ = write!(out, "{:08X}", c as u32);
                    }
                }
                out.push_str("\\X0\\");
            }
        }
    }
    out.push('\'');
    out
}

fn logical(b: bool) -> &'static str {
    if b {
        ".T."
    } else {
        ".F."
    }
}

fn coords(p: DVec3) -> String {
    format!("({},{},{})", real(p.x), real(p.y), real(p.z))
}

fn ref_list(ids: &[u64]) -> String {
    let v: Vec<String> = ids.iter().map(|i| format!("#{i}")).collect();
    format!("({})", v.join(","))
}

fn real_list(xs: &[f64]) -> String {
    let v: Vec<String> = xs.iter().map(|&x| real(x)).collect();
    format!("({})", v.join(","))
}

fn int_list(xs: &[usize]) -> String {
    let v: Vec<String> = xs.iter().map(|x| x.to_string()).collect();
    format!("({})", v.join(","))
}

/// Expanded knots → (multiplicities, distinct knots), runs of equal values
/// merged.
pub fn compress_knots(knots: &[f64]) -> (Vec<usize>, Vec<f64>) {
    let mut mults: Vec<usize> = Vec::new();
    let mut ks: Vec<f64> = Vec::new();
    for &k in knots {
        match ks.last() {
            Some(&last) if last == k => {
                if let Some(m) = mults.last_mut() {
                    *m += 1;
                }
            }
            _ => {
                ks.push(k);
                mults.push(1);
            }
        }
    }
    (mults, ks)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_read_back_exactly() {
        assert_eq!(real(1.0), "1.");
        assert_eq!(real(-0.0), "-0.");
        assert_eq!(real(0.25), "0.25");
        assert_eq!(real(1e-7), "1.E-7");
        assert_eq!(real(-2.5e20), "-2.5E20");
        assert_eq!(real(f64::NAN), "0.");
        for x in [
            0.1,
            1.0 / 3.0,
            std::f64::consts::PI,
            1e300,
            5e-324,
            -123456.789e-12,
            f64::MAX,
            f64::MIN_POSITIVE,
        ] {
            let s = real(x);
            assert!(s.contains('.'), "{s}");
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
        }
    }

    #[test]
    fn strings_escape() {
        assert_eq!(string("a'b\\c"), "'a''b\\\\c'");
        assert_eq!(string("é"), "'\\X2\\00E9\\X0\\'");
        assert_eq!(
            crate::p21::decode_string(string("x'é😀\\y").trim_matches('\'').as_bytes()),
            "x'é😀\\y"
        );
    }

    #[test]
    fn knots_compress() {
        let (m, k) = compress_knots(&[0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0]);
        assert_eq!(m, vec![3, 1, 3]);
        assert_eq!(k, vec![0.0, 0.5, 1.0]);
    }
}
