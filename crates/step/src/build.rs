//! From parsed entities to a [`Brep`] in millimetres: topology, geometry,
//! units and assemblies.

use std::collections::{HashMap, HashSet};

use glam::{DMat4, DVec3};
use thinplan_brep::{Brep, Coedge, Curve, Edge, EdgeId, Face, Frame, Loop, Shell, Solid, Surface};

use crate::check::{self, Expect};
use crate::p21::{Entity, Exchange, Part, Value};
use crate::{Limits, Place, StepErrorKind};

type R<T> = Result<T, StepErrorKind>;

pub(crate) struct Built {
    pub brep: Brep,
    pub units: String,
    pub warnings: Vec<String>,
}

/// Length and angle units of one representation context.
#[derive(Debug, Clone)]
struct Units {
    /// Millimetres per file length unit.
    length: f64,
    /// Radians per file angle unit.
    angle: f64,
    name: String,
    declared: bool,
}

impl Units {
    fn mm() -> Units {
        Units {
            length: 1.0,
            angle: 1.0,
            name: "mm".into(),
            declared: false,
        }
    }
}

/// A curve as read, or the name of a kind we do not model.
enum CurveOut {
    Known { curve: Curve, reversed: bool },
    Unknown(String),
}

/// Per-representation geometry state: scale and the deduplication maps.
struct Geo {
    scale: f64,
    angle: f64,
    brep: Brep,
    vertices: HashMap<usize, usize>,
    edges: HashMap<usize, EdgeId>,
    poly_vertices: HashMap<usize, usize>,
    poly_edges: HashMap<(usize, usize), EdgeId>,
    /// Per B-rep edge, the entity ids it was read from (for messages).
    edge_src: Vec<EdgeSrc>,
    /// Per B-rep face, the id of its `ADVANCED_FACE` / `FACE_SURFACE`.
    face_src: Vec<u64>,
}

/// Where a B-rep edge came from.
#[derive(Debug, Clone, Copy)]
enum EdgeSrc {
    Curve(u64),
    /// A `POLY_LOOP` side between two points.
    Poly(u64, u64),
}

/// Names B-rep pieces by the file's entity ids.
struct FileNames<'g> {
    edges: &'g [EdgeSrc],
    faces: &'g [u64],
}

impl check::Names for FileNames<'_> {
    fn edge(&self, e: EdgeId) -> String {
        match self.edges.get(e) {
            Some(EdgeSrc::Curve(id)) => format!("#{id}"),
            Some(EdgeSrc::Poly(a, b)) => format!("#{a}-#{b} (a POLY_LOOP side)"),
            None => format!("{e} (internal)"),
        }
    }
    fn face(&self, f: usize) -> String {
        match self.faces.get(f) {
            Some(id) => format!("#{id}"),
            None => format!("{f} (internal)"),
        }
    }
}

impl Geo {
    fn new(u: &Units) -> Geo {
        Geo {
            scale: u.length,
            angle: u.angle,
            brep: Brep::new(),
            vertices: HashMap::new(),
            edges: HashMap::new(),
            poly_vertices: HashMap::new(),
            poly_edges: HashMap::new(),
            edge_src: Vec::new(),
            face_src: Vec::new(),
        }
    }
}

/// Arguments of one partial record, with error helpers naming the entity.
#[derive(Clone, Copy)]
struct A<'x, 'a> {
    ex: &'x Exchange<'a>,
    idx: usize,
    ty: &'x str,
    vals: &'x [Value],
}

fn place_of(ex: &Exchange<'_>, idx: usize) -> Place {
    match ex.entities.get(idx) {
        Some(e) => {
            let (line, column) = ex.line_col(e.offset as usize);
            Place {
                id: Some(e.id),
                line,
                column,
            }
        }
        None => Place {
            id: None,
            line: 0,
            column: 0,
        },
    }
}

fn resolve_from(ex: &Exchange<'_>, from: usize, v: &Value) -> R<usize> {
    match v {
        Value::Ref(id) => ex.index_of(*id).ok_or_else(|| StepErrorKind::Dangling {
            place: place_of(ex, from),
            target: *id,
        }),
        _ => {
            let ty = ex
                .entities
                .get(from)
                .and_then(|e| ex.parts_of(e).first())
                .map(|p| ex.name(p.name))
                .unwrap_or("");
            Err(StepErrorKind::WrongParameter {
                place: place_of(ex, from),
                entity: ty.to_string(),
                reason: format!("expected a reference, found {}", describe(v)),
            })
        }
    }
}

fn describe(v: &Value) -> &'static str {
    match v {
        Value::Ref(_) => "a reference",
        Value::Int(_) => "an integer",
        Value::Real(_) => "a real",
        Value::Str(_) => "a string",
        Value::Enum(_) => "an enumeration",
        Value::Binary(_) => "a binary",
        Value::Null => "$",
        Value::Derived => "*",
        Value::List(_) => "a list",
        Value::Typed { .. } => "a typed parameter",
    }
}

impl<'x, 'a> A<'x, 'a> {
    fn wrong(&self, reason: impl Into<String>) -> StepErrorKind {
        StepErrorKind::WrongParameter {
            place: place_of(self.ex, self.idx),
            entity: self.ty.to_string(),
            reason: reason.into(),
        }
    }

    fn get(&self, i: usize) -> R<&'x Value> {
        self.vals.get(i).ok_or_else(|| {
            self.wrong(format!(
                "expected at least {} parameters, found {}",
                i + 1,
                self.vals.len()
            ))
        })
    }

    fn value_num(&self, v: &Value, what: &str) -> R<f64> {
        let x = match v {
            Value::Int(i) => *i as f64,
            Value::Real(r) => *r,
            Value::Typed { args, .. } => match self.ex.list(*args) {
                [inner] => return self.value_num(inner, what),
                _ => return Err(self.wrong(format!("{what}: expected a number"))),
            },
            other => {
                return Err(self.wrong(format!(
                    "{what}: expected a number, found {}",
                    describe(other)
                )))
            }
        };
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.wrong(format!("{what}: number out of range")))
        }
    }

    fn num(&self, i: usize) -> R<f64> {
        self.value_num(self.get(i)?, &format!("parameter {}", i + 1))
    }

    fn int(&self, i: usize) -> R<i64> {
        match self.get(i)? {
            Value::Int(v) => Ok(*v),
            Value::Real(r) if r.fract() == 0.0 && r.abs() < 1e15 => Ok(*r as i64),
            other => Err(self.wrong(format!(
                "parameter {}: expected an integer, found {}",
                i + 1,
                describe(other)
            ))),
        }
    }

    fn logical(&self, i: usize) -> R<bool> {
        match self.get(i)? {
            Value::Enum(s) => match self.ex.raw(*s) {
                b"T" | b"TRUE" | b"U" | b"UNKNOWN" => Ok(true),
                b"F" | b"FALSE" => Ok(false),
                _ => Err(self.wrong(format!("parameter {}: expected .T. or .F.", i + 1))),
            },
            other => Err(self.wrong(format!(
                "parameter {}: expected .T. or .F., found {}",
                i + 1,
                describe(other)
            ))),
        }
    }

    fn r(&self, i: usize) -> R<usize> {
        resolve_from(self.ex, self.idx, self.get(i)?)
    }

    fn opt_r(&self, i: usize) -> R<Option<usize>> {
        match self.vals.get(i) {
            None | Some(Value::Null) | Some(Value::Derived) => Ok(None),
            Some(v) => resolve_from(self.ex, self.idx, v).map(Some),
        }
    }

    fn list(&self, i: usize) -> R<&'x [Value]> {
        match self.get(i)? {
            Value::List(l) => Ok(self.ex.list(*l)),
            other => Err(self.wrong(format!(
                "parameter {}: expected a list, found {}",
                i + 1,
                describe(other)
            ))),
        }
    }

    fn refs(&self, i: usize) -> R<Vec<usize>> {
        self.list(i)?
            .iter()
            .map(|v| resolve_from(self.ex, self.idx, v))
            .collect()
    }

    fn string(&self, i: usize) -> String {
        match self.vals.get(i) {
            Some(Value::Str(s)) => self.ex.string(*s).into_owned(),
            _ => String::new(),
        }
    }
}

struct Ctx<'x, 'a> {
    ex: &'x Exchange<'a>,
    limits: Limits,
    work: u64,
    warnings: Vec<String>,
    warned: HashSet<String>,
    /// Entities whose resolution is in progress (cycle detection).
    active: Vec<bool>,
    /// The entities being resolved, outermost first.
    path: Vec<usize>,
    geo: Geo,
    unit_cache: HashMap<usize, Units>,
    /// Why each shell outside a solid is not closed (file order).
    open_shells: Vec<StepErrorKind>,
}

const SOLID_TYPES: [&str; 3] = ["MANIFOLD_SOLID_BREP", "BREP_WITH_VOIDS", "FACETED_BREP"];

impl<'x, 'a> Ctx<'x, 'a> {
    fn warn(&mut self, key: &str, msg: String) {
        if self.warned.insert(key.to_string()) {
            self.warnings.push(msg);
        }
    }

    fn tick(&mut self, n: u64, idx: usize) -> R<()> {
        self.work = self.work.saturating_add(n);
        if self.work > self.limits.max_work {
            return Err(StepErrorKind::Limit {
                place: place_of(self.ex, idx),
                reason: format!("more than {} units of work (limit)", self.limits.max_work),
            });
        }
        Ok(())
    }

    fn ent(&self, idx: usize) -> Option<&'x Entity> {
        self.ex.entities.get(idx)
    }

    /// The type name of a simple entity, or "" for a complex one.
    fn head(&self, idx: usize) -> &'x str {
        let ex: &'x Exchange<'a> = self.ex;
        match ex.entities.get(idx) {
            Some(e) if !e.complex => ex
                .parts_of(e)
                .first()
                .map(|p| ex.name(p.name))
                .unwrap_or(""),
            _ => "",
        }
    }

    /// A readable type name: the simple name, or `(A B C)` for complex ones.
    fn type_label(&self, idx: usize) -> String {
        let ex = self.ex;
        match ex.entities.get(idx) {
            Some(e) if e.complex => {
                let names: Vec<&str> = ex.parts_of(e).iter().map(|p| ex.name(p.name)).collect();
                format!("({})", names.join(" "))
            }
            Some(_) => self.head(idx).to_string(),
            None => String::new(),
        }
    }

    fn part(&self, idx: usize, name: &str) -> Option<&'x Part> {
        let ex: &'x Exchange<'a> = self.ex;
        ex.entities.get(idx).and_then(|e| ex.part(e, name))
    }

    fn has_part(&self, idx: usize, name: &str) -> bool {
        self.part(idx, name).is_some()
    }

    /// Arguments of the simple entity at `idx` (or its part named like its head).
    fn args(&self, idx: usize) -> A<'x, 'a> {
        let ex: &'x Exchange<'a> = self.ex;
        let (ty, vals) = match ex.entities.get(idx) {
            Some(e) => match ex.parts_of(e).first() {
                Some(p) => (ex.name(p.name), ex.args(p)),
                None => ("", &[][..]),
            },
            None => ("", &[][..]),
        };
        A { ex, idx, ty, vals }
    }

    /// Arguments of the partial record `name` of the entity at `idx`.
    fn part_args(&self, idx: usize, name: &'x str) -> Option<A<'x, 'a>> {
        let ex: &'x Exchange<'a> = self.ex;
        self.part(idx, name).map(|p| A {
            ex,
            idx,
            ty: name,
            vals: ex.args(p),
        })
    }

    fn expect_type(&self, idx: usize, types: &[&str], role: &str) -> R<A<'x, 'a>> {
        let a = self.args(idx);
        if types.contains(&self.head(idx)) {
            Ok(a)
        } else {
            Err(StepErrorKind::WrongParameter {
                place: place_of(self.ex, idx),
                entity: self.type_label(idx),
                reason: format!("expected {role} ({})", types.join(" or ")),
            })
        }
    }

    /// The error for an entity of the wrong kind in a topological position:
    /// "unsupported" for another entity of the same family (a `SUBEDGE`
    /// where an edge is expected), "wrong parameter" for anything else.
    fn bad_kind(&self, idx: usize, types: &[&str], role: &str) -> StepErrorKind {
        let label = self.type_label(idx);
        let family = ["EDGE", "LOOP", "FACE", "SHELL", "PATH"];
        let same_family = family
            .iter()
            .any(|f| label.contains(f) && types.iter().any(|t| t.contains(f)));
        let reason = format!("expected {role} ({})", types.join(" or "));
        if same_family {
            self.unsupported(idx, reason)
        } else {
            StepErrorKind::WrongParameter {
                place: place_of(self.ex, idx),
                entity: label,
                reason,
            }
        }
    }

    fn unsupported(&self, idx: usize, reason: impl Into<String>) -> StepErrorKind {
        StepErrorKind::Unsupported {
            place: place_of(self.ex, idx),
            entity: self.type_label(idx),
            reason: reason.into(),
        }
    }

    /// Marks `idx` as being resolved; errors on a cycle or too deep a chain.
    fn enter(&mut self, idx: usize, from: usize) -> R<()> {
        if self.active.get(idx).copied().unwrap_or(false) {
            let id = |i: usize| self.ent(i).map(|e| e.id).unwrap_or(0);
            let mut chain: Vec<String> = self
                .path
                .iter()
                .skip_while(|&&p| p != idx)
                .map(|&p| format!("#{}", id(p)))
                .collect();
            chain.push(format!("#{}", id(idx)));
            return Err(StepErrorKind::Cyclic {
                place: place_of(self.ex, from),
                chain: format!("references loop back: {}", chain.join(" -> ")),
            });
        }
        if self.path.len() >= self.limits.max_depth {
            return Err(StepErrorKind::Limit {
                place: place_of(self.ex, idx),
                reason: format!("references nested deeper than {}", self.limits.max_depth),
            });
        }
        if let Some(a) = self.active.get_mut(idx) {
            *a = true;
        }
        self.path.push(idx);
        Ok(())
    }

    fn leave(&mut self, idx: usize) {
        if let Some(a) = self.active.get_mut(idx) {
            *a = false;
        }
        self.path.pop();
    }

    // ---------------------------------------------------------------- geometry

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

    fn point(&mut self, idx: usize) -> R<DVec3> {
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
    fn vector(&mut self, idx: usize) -> R<(DVec3, f64)> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["VECTOR"], "a vector")?;
        let d = self.direction(a.r(1)?)?;
        let m = a.num(2)? * self.geo.scale;
        Ok((d.try_normalize().unwrap_or(DVec3::Z), m))
    }

    fn placement(&mut self, idx: usize) -> R<Frame> {
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

    fn axis1(&mut self, idx: usize) -> R<(DVec3, DVec3)> {
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["AXIS1_PLACEMENT"], "an axis placement")?;
        let origin = self.point(a.r(1)?)?;
        let axis = match a.opt_r(2)? {
            Some(i) => self.direction(i)?,
            None => DVec3::Z,
        };
        Ok((origin, axis.try_normalize().unwrap_or(DVec3::Z)))
    }

    fn length(&self, a: &A<'x, 'a>, i: usize) -> R<f64> {
        Ok(a.num(i)? * self.geo.scale)
    }

    fn expand_knots(
        &mut self,
        a: &A<'x, 'a>,
        mults: usize,
        knots: usize,
        n_expected: usize,
    ) -> R<Vec<f64>> {
        let m = a.list(mults)?;
        let k = a.list(knots)?;
        if m.len() != k.len() {
            return Err(a.wrong(format!(
                "{} knot multiplicities for {} knots",
                m.len(),
                k.len()
            )));
        }
        let bound = n_expected.saturating_mul(4).saturating_add(64);
        let mut out = Vec::with_capacity(n_expected.min(1 << 20));
        for (mv, kv) in m.iter().zip(k) {
            let mult = match mv {
                Value::Int(i) if *i >= 0 => *i as usize,
                _ => return Err(a.wrong("knot multiplicity must be a non-negative integer")),
            };
            let knot = a.value_num(kv, "knot")?;
            if out.len().saturating_add(mult) > bound {
                return Err(a.wrong(format!(
                    "knot multiplicities add up to more than {bound} for {n_expected} expected knots"
                )));
            }
            out.extend(std::iter::repeat_n(knot, mult));
        }
        self.tick(out.len() as u64, a.idx)?;
        // Evaluation searches the knots by bisection, which decreasing knots
        // would send round for ever.
        if out.windows(2).any(|w| w[1] < w[0]) {
            return Err(a.wrong("knots decrease"));
        }
        if out.len() != n_expected {
            let id = self.ent(a.idx).map(|e| e.id).unwrap_or(0);
            self.warn(
                &format!("knots#{id}"),
                format!(
                    "#{id}: {} knots after expansion, {n_expected} expected (control points + degree + 1)",
                    out.len()
                ),
            );
        }
        Ok(out)
    }

    fn degree(&self, a: &A<'x, 'a>, i: usize) -> R<usize> {
        let d = a.int(i)?;
        if !(0..=64).contains(&d) {
            return Err(a.wrong(format!("B-spline degree {d} out of range")));
        }
        Ok(d as usize)
    }

    fn points(&mut self, a: &A<'x, 'a>, i: usize) -> R<Vec<DVec3>> {
        let refs = a.refs(i)?;
        refs.into_iter().map(|r| self.point(r)).collect()
    }

    fn bspline_curve(&mut self, idx: usize) -> R<Curve> {
        // Simple: B_SPLINE_CURVE_WITH_KNOTS(name, degree, cps, form, closed, si, mults, knots, spec)
        // Complex: B_SPLINE_CURVE(degree, cps, form, closed, si)
        //          B_SPLINE_CURVE_WITH_KNOTS(mults, knots, spec)
        //          RATIONAL_B_SPLINE_CURVE(weights)
        let (base, base_off, knots, knots_off) = if self.head(idx) == "B_SPLINE_CURVE_WITH_KNOTS" {
            let a = self.args(idx);
            (a, 1, a, 6)
        } else {
            match (
                self.part_args(idx, "B_SPLINE_CURVE"),
                self.part_args(idx, "B_SPLINE_CURVE_WITH_KNOTS"),
            ) {
                (Some(b), Some(k)) => (b, 0, k, 0),
                _ => {
                    return Err(self.unsupported(idx, "B-spline curve without knots"));
                }
            }
        };
        let degree = self.degree(&base, base_off)?;
        let control_points = self.points(&base, base_off + 1)?;
        let n = control_points.len() + degree + 1;
        let knots = self.expand_knots(&knots, knots_off, knots_off + 1, n)?;
        let weights = match self.part_args(idx, "RATIONAL_B_SPLINE_CURVE") {
            Some(w) => {
                let l = w.list(0)?;
                let ws = l
                    .iter()
                    .map(|v| w.value_num(v, "weight"))
                    .collect::<R<Vec<f64>>>()?;
                if ws.len() != control_points.len() {
                    return Err(w.wrong(format!(
                        "{} weights for {} control points",
                        ws.len(),
                        control_points.len()
                    )));
                }
                ws
            }
            None => Vec::new(),
        };
        Ok(Curve::BSpline {
            degree,
            control_points,
            knots,
            weights,
        })
    }

    fn curve(&mut self, idx: usize, from: usize) -> R<CurveOut> {
        self.tick(1, idx)?;
        self.enter(idx, from)?;
        let r = self.curve_inner(idx);
        self.leave(idx);
        r
    }

    fn curve_inner(&mut self, idx: usize) -> R<CurveOut> {
        let a = self.args(idx);
        let known = |curve| {
            Ok(CurveOut::Known {
                curve,
                reversed: false,
            })
        };
        match self.head(idx) {
            "LINE" => {
                let origin = self.point(a.r(1)?)?;
                let (dir, _) = self.vector(a.r(2)?)?;
                known(Curve::Line { origin, dir })
            }
            "CIRCLE" => {
                let p = a.r(1)?;
                if self.head(p) != "AXIS2_PLACEMENT_3D" {
                    return Ok(CurveOut::Unknown("CIRCLE (2D)".into()));
                }
                let frame = self.placement(p)?;
                let radius = self.length(&a, 2)?;
                known(Curve::Circle { frame, radius })
            }
            "ELLIPSE" => {
                let p = a.r(1)?;
                if self.head(p) != "AXIS2_PLACEMENT_3D" {
                    return Ok(CurveOut::Unknown("ELLIPSE (2D)".into()));
                }
                let frame = self.placement(p)?;
                let semi_axis_1 = self.length(&a, 2)?;
                let semi_axis_2 = self.length(&a, 3)?;
                known(Curve::Ellipse {
                    frame,
                    semi_axis_1,
                    semi_axis_2,
                })
            }
            "B_SPLINE_CURVE_WITH_KNOTS" => known(self.bspline_curve(idx)?),
            "POLYLINE" => {
                let points = self.points(&a, 1)?;
                known(Curve::Polyline { points })
            }
            "SURFACE_CURVE" | "SEAM_CURVE" | "INTERSECTION_CURVE" | "BOUNDED_SURFACE_CURVE" => {
                self.curve(a.r(1)?, idx)
            }
            "TRIMMED_CURVE" => {
                let basis = a.r(1)?;
                let sense = a.logical(4).unwrap_or(true);
                Ok(match self.curve(basis, idx)? {
                    CurveOut::Known { curve, reversed } => CurveOut::Known {
                        curve,
                        reversed: reversed ^ !sense,
                    },
                    u => u,
                })
            }
            "" => {
                if self.has_part(idx, "B_SPLINE_CURVE") {
                    known(self.bspline_curve(idx)?)
                } else {
                    Ok(CurveOut::Unknown(self.type_label(idx)))
                }
            }
            other => Ok(CurveOut::Unknown(other.to_string())),
        }
    }

    fn bspline_surface(&mut self, idx: usize) -> R<Surface> {
        // Simple: (name, ud, vd, cps, form, uc, vc, si, umults, vmults, uknots, vknots, spec)
        let (base, bo, knots, ko) = if self.head(idx) == "B_SPLINE_SURFACE_WITH_KNOTS" {
            let a = self.args(idx);
            (a, 1, a, 8)
        } else {
            match (
                self.part_args(idx, "B_SPLINE_SURFACE"),
                self.part_args(idx, "B_SPLINE_SURFACE_WITH_KNOTS"),
            ) {
                (Some(b), Some(k)) => (b, 0, k, 0),
                _ => {
                    return Ok(Surface::Other {
                        kind: self.type_label(idx),
                    })
                }
            }
        };
        let u_degree = self.degree(&base, bo)?;
        let v_degree = self.degree(&base, bo + 1)?;
        let rows = base.list(bo + 2)?;
        let mut control_points = Vec::with_capacity(rows.len());
        let mut width = None;
        for row in rows {
            let l = match row {
                Value::List(l) => self.ex.list(*l),
                _ => return Err(base.wrong("control points: expected a list of lists")),
            };
            if *width.get_or_insert(l.len()) != l.len() {
                return Err(base.wrong("control point rows of different lengths"));
            }
            let mut pts = Vec::with_capacity(l.len());
            for v in l {
                let r = resolve_from(self.ex, idx, v)?;
                pts.push(self.point(r)?);
            }
            control_points.push(pts);
        }
        let nu = control_points.len();
        let nv = width.unwrap_or(0);
        let u_knots = self.expand_knots(&knots, ko, ko + 2, nu + u_degree + 1)?;
        let v_knots = self.expand_knots(&knots, ko + 1, ko + 3, nv + v_degree + 1)?;
        let weights = match self.part_args(idx, "RATIONAL_B_SPLINE_SURFACE") {
            Some(w) => {
                let mut out = Vec::new();
                for row in w.list(0)? {
                    let l = match row {
                        Value::List(l) => self.ex.list(*l),
                        _ => return Err(w.wrong("weights: expected a list of lists")),
                    };
                    let r = l
                        .iter()
                        .map(|v| w.value_num(v, "weight"))
                        .collect::<R<Vec<f64>>>()?;
                    if r.len() != nv {
                        return Err(w.wrong("weights do not match the control points"));
                    }
                    out.push(r);
                }
                if out.len() != nu {
                    return Err(w.wrong("weights do not match the control points"));
                }
                out
            }
            None => Vec::new(),
        };
        Ok(Surface::BSpline {
            u_degree,
            v_degree,
            control_points,
            u_knots,
            v_knots,
            weights,
        })
    }

    fn surface(&mut self, idx: usize, from: usize) -> R<Surface> {
        self.tick(1, idx)?;
        self.enter(idx, from)?;
        let r = self.surface_inner(idx);
        self.leave(idx);
        r
    }

    fn surface_inner(&mut self, idx: usize) -> R<Surface> {
        let a = self.args(idx);
        Ok(match self.head(idx) {
            "PLANE" => Surface::Plane {
                frame: self.placement(a.r(1)?)?,
            },
            "CYLINDRICAL_SURFACE" => Surface::Cylinder {
                frame: self.placement(a.r(1)?)?,
                radius: self.length(&a, 2)?,
            },
            "CONICAL_SURFACE" => Surface::Cone {
                frame: self.placement(a.r(1)?)?,
                radius: self.length(&a, 2)?,
                semi_angle: a.num(3)? * self.geo.angle,
            },
            "SPHERICAL_SURFACE" => Surface::Sphere {
                frame: self.placement(a.r(1)?)?,
                radius: self.length(&a, 2)?,
            },
            "TOROIDAL_SURFACE" | "DEGENERATE_TOROIDAL_SURFACE" => Surface::Torus {
                frame: self.placement(a.r(1)?)?,
                major_radius: self.length(&a, 2)?,
                minor_radius: self.length(&a, 3)?,
            },
            "B_SPLINE_SURFACE_WITH_KNOTS" => self.bspline_surface(idx)?,
            "SURFACE_OF_LINEAR_EXTRUSION" => match self.curve(a.r(1)?, idx)? {
                CurveOut::Known { curve, .. } => {
                    let (d, m) = self.vector(a.r(2)?)?;
                    Surface::Extrusion {
                        curve: Box::new(curve),
                        dir: d * m,
                    }
                }
                CurveOut::Unknown(k) => Surface::Other {
                    kind: format!("SURFACE_OF_LINEAR_EXTRUSION of {k}"),
                },
            },
            "SURFACE_OF_REVOLUTION" => match self.curve(a.r(1)?, idx)? {
                CurveOut::Known { curve, .. } => {
                    let (axis_origin, axis_dir) = self.axis1(a.r(2)?)?;
                    Surface::Revolution {
                        curve: Box::new(curve),
                        axis_origin,
                        axis_dir,
                    }
                }
                CurveOut::Unknown(k) => Surface::Other {
                    kind: format!("SURFACE_OF_REVOLUTION of {k}"),
                },
            },
            "" if self.has_part(idx, "B_SPLINE_SURFACE") => self.bspline_surface(idx)?,
            _ => {
                let kind = self.type_label(idx);
                self.warn(
                    &format!("surface:{kind}"),
                    format!("surface kind {kind} kept by name only"),
                );
                Surface::Other { kind }
            }
        })
    }

    // ---------------------------------------------------------------- topology

    fn vertex(&mut self, idx: usize) -> R<usize> {
        if let Some(&v) = self.geo.vertices.get(&idx) {
            return Ok(v);
        }
        self.tick(1, idx)?;
        let a = self.expect_type(idx, &["VERTEX_POINT"], "a vertex")?;
        let p = self.point(a.r(1)?)?;
        let v = self.geo.brep.add_vertex(p);
        self.geo.vertices.insert(idx, v);
        Ok(v)
    }

    fn edge(&mut self, idx: usize) -> R<EdgeId> {
        if let Some(&e) = self.geo.edges.get(&idx) {
            return Ok(e);
        }
        self.tick(1, idx)?;
        if self.head(idx) != "EDGE_CURVE" {
            return Err(self.bad_kind(idx, &["EDGE_CURVE"], "an edge"));
        }
        let a = self.args(idx);
        let start = self.vertex(a.r(1)?)?;
        let end = self.vertex(a.r(2)?)?;
        let same_sense = a.logical(4)?;
        let (curve, reversed) = match self.curve(a.r(3)?, idx)? {
            CurveOut::Known { curve, reversed } => (curve, reversed),
            CurveOut::Unknown(kind) => {
                self.warn(
                    &format!("curve:{kind}"),
                    format!("curve kind {kind} replaced by a polyline through its edge's vertices"),
                );
                let b = &self.geo.brep;
                let pts = match (b.vertices.get(start), b.vertices.get(end)) {
                    (Some(s), Some(e)) => vec![s.point, e.point],
                    _ => Vec::new(),
                };
                (Curve::Polyline { points: pts }, false)
            }
        };
        let e = self.geo.brep.add_edge(Edge {
            start,
            end,
            curve,
            same_sense: same_sense ^ reversed,
        });
        let id = self.ent(idx).map(|x| x.id).unwrap_or(0);
        self.geo.edge_src.push(EdgeSrc::Curve(id));
        self.geo.edges.insert(idx, e);
        Ok(e)
    }

    fn oriented_edge(&mut self, idx: usize, from: usize) -> R<Coedge> {
        self.tick(1, idx)?;
        match self.head(idx) {
            "ORIENTED_EDGE" => {
                let a = self.args(idx);
                let element = a.r(3)?;
                let orientation = a.logical(4)?;
                self.enter(idx, from)?;
                let inner = if self.head(element) == "ORIENTED_EDGE" {
                    self.oriented_edge(element, idx)
                } else {
                    self.edge(element).map(|edge| Coedge {
                        edge,
                        forward: true,
                    })
                };
                self.leave(idx);
                let c = inner?;
                Ok(Coedge {
                    edge: c.edge,
                    forward: c.forward == orientation,
                })
            }
            "EDGE_CURVE" => Ok(Coedge {
                edge: self.edge(idx)?,
                forward: true,
            }),
            _ => Err(self.bad_kind(idx, &["ORIENTED_EDGE"], "an oriented edge")),
        }
    }

    fn poly_vertex(&mut self, pidx: usize) -> R<usize> {
        if let Some(&v) = self.geo.poly_vertices.get(&pidx) {
            return Ok(v);
        }
        let p = self.point(pidx)?;
        let v = self.geo.brep.add_vertex(p);
        self.geo.poly_vertices.insert(pidx, v);
        Ok(v)
    }

    fn lp(&mut self, idx: usize, outer: bool, orientation: bool) -> R<Loop> {
        self.tick(1, idx)?;
        let a = self.args(idx);
        let mut l = Loop {
            coedges: Vec::new(),
            vertex: None,
            orientation,
            outer,
        };
        match self.head(idx) {
            "EDGE_LOOP" => {
                for r in a.refs(1)? {
                    let c = self.oriented_edge(r, idx)?;
                    l.coedges.push(c);
                }
            }
            "VERTEX_LOOP" => l.vertex = Some(self.vertex(a.r(1)?)?),
            "POLY_LOOP" => {
                let pts = a.refs(1)?;
                let n = pts.len();
                for i in 0..n {
                    let (pa, pb) = (pts[i], pts[(i + 1) % n]);
                    let key = (pa.min(pb), pa.max(pb));
                    let forward = pa <= pb;
                    let edge = match self.geo.poly_edges.get(&key) {
                        Some(&e) => e,
                        None => {
                            let start = self.poly_vertex(key.0)?;
                            let end = self.poly_vertex(key.1)?;
                            let (ps, pe) = (
                                self.geo.brep.vertices[start].point,
                                self.geo.brep.vertices[end].point,
                            );
                            let dir = (pe - ps).try_normalize().unwrap_or(DVec3::X);
                            let e = self.geo.brep.add_edge(Edge {
                                start,
                                end,
                                curve: Curve::Line { origin: ps, dir },
                                same_sense: true,
                            });
                            let id = |i: usize| self.ent(i).map(|x| x.id).unwrap_or(0);
                            let src = EdgeSrc::Poly(id(key.0), id(key.1));
                            self.geo.edge_src.push(src);
                            self.geo.poly_edges.insert(key, e);
                            e
                        }
                    };
                    l.coedges.push(Coedge { edge, forward });
                }
            }
            _ => {
                return Err(self.bad_kind(
                    idx,
                    &["EDGE_LOOP", "VERTEX_LOOP", "POLY_LOOP"],
                    "a loop",
                ))
            }
        }
        Ok(l)
    }

    fn face(&mut self, idx: usize, from: usize) -> R<usize> {
        self.tick(1, idx)?;
        let a = self.args(idx);
        match self.head(idx) {
            "ADVANCED_FACE" | "FACE_SURFACE" => {
                let name = a.string(0);
                let bounds = a.refs(1)?;
                let surface = self.surface(a.r(2)?, idx)?;
                let same_sense = a.logical(3)?;
                let mut loops = Vec::with_capacity(bounds.len());
                for b in bounds {
                    let ba =
                        self.expect_type(b, &["FACE_OUTER_BOUND", "FACE_BOUND"], "a face bound")?;
                    let outer = ba.ty == "FACE_OUTER_BOUND";
                    let orientation = ba.logical(2)?;
                    let l = self.lp(ba.r(1)?, outer, orientation)?;
                    loops.push(self.geo.brep.add_loop(l));
                }
                let id = self.ent(idx).map(|x| x.id).unwrap_or(0);
                self.geo.face_src.push(id);
                Ok(self.geo.brep.add_face(Face {
                    surface,
                    same_sense,
                    loops,
                    name,
                }))
            }
            "ORIENTED_FACE" => {
                let element = a.r(2)?;
                let orientation = a.logical(3)?;
                self.enter(idx, from)?;
                let f = self.face(element, idx);
                self.leave(idx);
                let f = f?;
                if !orientation {
                    self.reverse_face(f);
                }
                Ok(f)
            }
            _ => Err(self.bad_kind(idx, &["ADVANCED_FACE", "FACE_SURFACE"], "a face")),
        }
    }

    /// Turns a face over: its normal and its bounds (`ORIENTED_FACE(.F.)`).
    fn reverse_face(&mut self, f: usize) {
        let b = &mut self.geo.brep;
        if let Some(face) = b.faces.get_mut(f) {
            face.same_sense = !face.same_sense;
            for &l in &face.loops {
                if let Some(lp) = b.loops.get_mut(l) {
                    lp.orientation = !lp.orientation;
                }
            }
        }
    }

    /// Builds a shell; returns its id and the `CLOSED_SHELL` / `OPEN_SHELL`
    /// entity it came from. Oriented shells turn their faces over.
    fn shell(&mut self, idx: usize, from: usize) -> R<(usize, usize)> {
        self.tick(1, idx)?;
        let a = self.args(idx);
        match self.head(idx) {
            "CLOSED_SHELL" | "OPEN_SHELL" => {
                let closed = a.ty == "CLOSED_SHELL";
                let mut faces = Vec::new();
                let mut seen = HashSet::new();
                let mut repeated = Vec::new();
                for f in a.refs(1)? {
                    // The same face listed twice is an exporter's slip: the
                    // copy would use every edge of the face twice more.
                    if !seen.insert(f) {
                        repeated.push(f);
                        continue;
                    }
                    faces.push(self.face(f, idx)?);
                }
                if !repeated.is_empty() {
                    let id = |i: usize| self.ent(i).map(|e| e.id).unwrap_or(0);
                    let mut ids: Vec<String> = repeated
                        .iter()
                        .take(10)
                        .map(|&f| format!("#{}", id(f)))
                        .collect();
                    if repeated.len() > 10 {
                        ids.push(format!("and {} more", repeated.len() - 10));
                    }
                    let shell_id = id(idx);
                    self.warnings.push(format!(
                        "#{shell_id} {}: face{} {} listed twice; the repeat dropped",
                        a.ty,
                        if repeated.len() == 1 { "" } else { "s" },
                        ids.join(", ")
                    ));
                }
                Ok((self.geo.brep.add_shell(Shell { faces, closed }), idx))
            }
            "ORIENTED_CLOSED_SHELL" | "ORIENTED_OPEN_SHELL" => {
                let element = a.r(2)?;
                let orientation = a.logical(3)?;
                self.enter(idx, from)?;
                let s = self.shell(element, idx);
                self.leave(idx);
                let (s, inner) = s?;
                if !orientation {
                    let faces = self.geo.brep.shells[s].faces.clone();
                    for f in faces {
                        self.reverse_face(f);
                    }
                }
                Ok((s, inner))
            }
            _ => Err(self.bad_kind(idx, &["CLOSED_SHELL", "OPEN_SHELL"], "a shell")),
        }
    }

    /// Runs the closed-solid checks on a shell; repairs become warnings.
    /// `owner` is the solid or surface model holding it (for messages).
    fn check_shell(&mut self, shell: usize, entity: usize, owner: usize, expect: Expect) -> R<()> {
        self.tick(check::work(&self.geo.brep, shell), entity)?;
        let names = FileNames {
            edges: &self.geo.edge_src,
            faces: &self.geo.face_src,
        };
        let what = self.shell_label(entity, owner);
        match check::check_shell(&mut self.geo.brep, shell, expect, &names) {
            Ok(ws) => {
                let place = place_of(self.ex, entity);
                for w in ws {
                    self.warnings.push(format!("{place} {what}: {w}"));
                }
                Ok(())
            }
            Err(reason) => Err(StepErrorKind::NotClosed {
                place: place_of(self.ex, entity),
                entity: what,
                reason,
            }),
        }
    }

    /// `CLOSED_SHELL of MANIFOLD_SOLID_BREP #159`.
    fn shell_label(&self, entity: usize, owner: usize) -> String {
        let id = self.ent(owner).map(|e| e.id).unwrap_or(0);
        let head = self.type_label(entity);
        if owner == entity {
            head
        } else {
            format!("{head} of {} #{id}", self.type_label(owner))
        }
    }

    fn solid(&mut self, idx: usize) -> R<()> {
        let a = self.args(idx);
        let name = a.string(0);
        let (outer, entity) = self.shell(a.r(1)?, idx)?;
        self.check_shell(outer, entity, idx, Expect::Outward)?;
        let mut shells = vec![outer];
        if a.ty == "BREP_WITH_VOIDS" {
            for v in a.refs(2)? {
                let (void, entity) = self.shell(v, idx)?;
                self.check_shell(void, entity, idx, Expect::Inward)?;
                shells.push(void);
            }
        }
        self.geo.brep.add_solid(Solid { shells, name });
        Ok(())
    }

    /// A shell outside any solid: kept, and marked closed when it closes.
    /// An open one is remembered; a file with nothing else is refused.
    fn loose_shell(&mut self, s: usize, entity: usize, owner: usize) -> R<()> {
        let mark = self.warnings.len();
        match self.check_shell(s, entity, owner, Expect::Outward) {
            Ok(()) => {
                self.geo.brep.shells[s].closed = true;
                Ok(())
            }
            Err(e @ StepErrorKind::NotClosed { .. }) => {
                self.warnings.truncate(mark);
                self.open_shells.push(e);
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    /// Adds a representation item: a solid, a surface model or a shell.
    /// Returns false for items that carry no B-rep.
    fn item(&mut self, idx: usize) -> R<bool> {
        let h = self.head(idx);
        if SOLID_TYPES.contains(&h) {
            self.solid(idx)?;
            Ok(true)
        } else if h == "SHELL_BASED_SURFACE_MODEL" {
            for s in self.args(idx).refs(1)? {
                let (shell, entity) = self.shell(s, idx)?;
                self.loose_shell(shell, entity, idx)?;
            }
            Ok(true)
        } else if matches!(
            h,
            "CLOSED_SHELL" | "OPEN_SHELL" | "ORIENTED_CLOSED_SHELL" | "ORIENTED_OPEN_SHELL"
        ) {
            let (shell, entity) = self.shell(idx, idx)?;
            self.loose_shell(shell, entity, entity)?;
            Ok(true)
        } else {
            Ok(false)
        }
    }

    // ------------------------------------------------------------------- units

    /// (kind, factor, name) of a unit: kind 'L' length (factor in mm),
    /// 'A' plane angle (factor in radians), '?' other. `None` for an entity
    /// that is no unit. A length or angle unit whose name is unknown or whose
    /// factor is not a positive finite number is an error naming it: a guess
    /// would scale the whole part.
    fn unit(&mut self, idx: usize, depth: usize) -> R<Option<(char, f64, String)>> {
        if depth > 8 {
            return Err(StepErrorKind::Limit {
                place: place_of(self.ex, idx),
                reason: "unit defined through more than 8 conversions".into(),
            });
        }
        self.tick(1, idx)?;
        let mut kind = if self.has_part(idx, "LENGTH_UNIT") {
            'L'
        } else if self.has_part(idx, "PLANE_ANGLE_UNIT") {
            'A'
        } else {
            '?'
        };
        let si = self
            .part_args(idx, "SI_UNIT")
            .or_else(|| (self.head(idx) == "SI_UNIT").then(|| self.args(idx)));
        if let Some(a) = si {
            let n = a.vals.len();
            if n < 2 {
                return Ok(None);
            }
            let (prefix, name) = (&a.vals[n - 2], &a.vals[n - 1]);
            let name = match name {
                Value::Enum(s) => self.ex.raw(*s),
                _ => return Ok(None),
            };
            let (p, sym) = match prefix {
                Value::Enum(s) => match self.ex.raw(*s) {
                    b"EXA" => (1e18, "E"),
                    b"PETA" => (1e15, "P"),
                    b"TERA" => (1e12, "T"),
                    b"GIGA" => (1e9, "G"),
                    b"MEGA" => (1e6, "M"),
                    b"KILO" => (1e3, "k"),
                    b"HECTO" => (1e2, "h"),
                    b"DECA" => (1e1, "da"),
                    b"DECI" => (1e-1, "d"),
                    b"CENTI" => (1e-2, "c"),
                    b"MILLI" => (1e-3, "m"),
                    b"MICRO" => (1e-6, "u"),
                    b"NANO" => (1e-9, "n"),
                    b"PICO" => (1e-12, "p"),
                    other if kind != '?' => {
                        return Err(a.wrong(format!(
                            "unknown SI prefix .{}.",
                            String::from_utf8_lossy(other)
                        )))
                    }
                    _ => (1.0, ""),
                },
                _ => (1.0, ""),
            };
            return match (name, kind) {
                (b"METRE", 'L' | '?') => Ok(Some(('L', 1000.0 * p, format!("{sym}m")))),
                (b"RADIAN", 'A' | '?') => Ok(Some(('A', p, format!("{sym}rad")))),
                (_, '?') => Ok(Some(('?', 1.0, String::new()))),
                (other, k) => Err(a.wrong(format!(
                    "unknown {} unit .{}.",
                    if k == 'L' { "length" } else { "plane angle" },
                    String::from_utf8_lossy(other)
                ))),
            };
        }
        let Some(cbu) = self
            .part_args(idx, "CONVERSION_BASED_UNIT")
            .or_else(|| (self.head(idx) == "CONVERSION_BASED_UNIT").then(|| self.args(idx)))
        else {
            return Ok(None);
        };
        let name = cbu.string(0);
        let lname = name.trim().to_ascii_lowercase();
        let known = match lname.as_str() {
            "inch" | "in" => Some(('L', 25.4)),
            "foot" | "ft" => Some(('L', 304.8)),
            "yard" => Some(('L', 914.4)),
            "mile" => Some(('L', 1_609_344.0)),
            "degree" | "deg" => Some(('A', std::f64::consts::PI / 180.0)),
            "grad" | "gon" => Some(('A', std::f64::consts::PI / 200.0)),
            _ => None,
        };
        // The conversion factor: (measure entity, kind, factor).
        let mut from_measure = None;
        if let Ok(Some(m)) = cbu.opt_r(1) {
            let ma = if self.head(m).is_empty() {
                self.part_args(m, "MEASURE_WITH_UNIT")
            } else {
                let a = self.args(m);
                a.vals
                    .len()
                    .checked_sub(2)
                    .and_then(|k| a.vals.get(k..))
                    .map(|vals| A { vals, ..a })
            };
            if let Some(ma) = ma {
                let value = ma.num(0)?;
                if let Ok(Some(inner)) = ma.opt_r(1) {
                    if let Some((k, f, _)) = self.unit(inner, depth + 1)? {
                        from_measure = Some((m, ma, k, value * f));
                    }
                }
            }
        }
        if kind == '?' {
            kind = from_measure
                .as_ref()
                .map(|m| m.2)
                .or(known.map(|k| k.0))
                .unwrap_or('?');
        }
        if kind == '?' {
            // Not a unit a part's geometry is measured in.
            return Ok(Some(('?', 1.0, lname)));
        }
        let factor = match (from_measure, known) {
            (Some((_, ma, _, f)), _) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(ma.wrong(format!(
                        "conversion factor {f} of unit '{name}' is not a positive number"
                    )));
                }
                f
            }
            (None, Some((_, f))) => f,
            (None, None) => {
                return Err(cbu.wrong(format!(
                    "unknown unit name '{name}' without a conversion factor"
                )))
            }
        };
        Ok(Some((kind, factor, lname)))
    }

    fn context_units(&mut self, ctx: Option<usize>) -> R<Units> {
        let Some(ctx) = ctx else {
            return Ok(Units::mm());
        };
        if let Some(u) = self.unit_cache.get(&ctx) {
            return Ok(u.clone());
        }
        let mut u = Units::mm();
        if let Some(a) = self.part_args(ctx, "GLOBAL_UNIT_ASSIGNED_CONTEXT") {
            if let Ok(list) = a.list(0) {
                for v in list {
                    let Ok(ui) = resolve_from(self.ex, ctx, v) else {
                        continue;
                    };
                    match self.unit(ui, 0)? {
                        Some(('L', f, name)) => {
                            u.length = f;
                            u.name = name;
                            u.declared = true;
                        }
                        Some(('A', f, _)) => u.angle = f,
                        _ => {}
                    }
                }
            }
        }
        self.unit_cache.insert(ctx, u.clone());
        Ok(u)
    }
}

// ---------------------------------------------------------------- assemblies

/// How a child representation is placed in its parent.
#[derive(Clone, Copy)]
enum Xf {
    Identity,
    /// Child-side placement (in child units), parent-side placement (in
    /// parent units): child → parent is `M(parent) · M(child)⁻¹`.
    Items {
        child: usize,
        parent: usize,
    },
}

#[derive(Clone, Copy)]
struct Link {
    child: usize,
    xf: Xf,
    /// The entity that made the link (for error messages).
    via: usize,
}

/// Representations in file order, their contents, and the B-rep items they hold.
type RepTable = (Vec<usize>, HashMap<usize, RepInfo>, HashSet<usize>);

struct RepInfo {
    items: Vec<usize>,
    context: Option<usize>,
    /// True when it has a solid, shell or surface model of its own.
    geometry: bool,
}

const REP_EXCLUDE: [&str; 3] = [
    "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION",
    "SHAPE_DEFINITION_REPRESENTATION",
    "DEFINITIONAL_REPRESENTATION",
];

impl<'x, 'a> Ctx<'x, 'a> {
    /// Items and context of a representation entity, if it is one.
    fn rep_args(&self, idx: usize) -> Option<A<'x, 'a>> {
        let h = self.head(idx);
        let a = if h.is_empty() {
            self.part_args(idx, "REPRESENTATION")?
        } else if (h.ends_with("SHAPE_REPRESENTATION") || h == "REPRESENTATION")
            && !REP_EXCLUDE.contains(&h)
        {
            self.args(idx)
        } else {
            return None;
        };
        (a.vals.len() == 3 && matches!(a.vals[1], Value::List(_))).then_some(a)
    }

    fn is_geometry_rep_type(&self, idx: usize) -> bool {
        matches!(
            self.head(idx),
            "ADVANCED_BREP_SHAPE_REPRESENTATION"
                | "MANIFOLD_SURFACE_SHAPE_REPRESENTATION"
                | "FACETED_BREP_SHAPE_REPRESENTATION"
                | "GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION"
        )
    }

    fn matrix_of(&mut self, placement: usize, units: &Units) -> R<DMat4> {
        match self.head(placement) {
            "AXIS2_PLACEMENT_3D" => {
                let saved = (self.geo.scale, self.geo.angle);
                self.geo.scale = units.length;
                let f = self.placement(placement);
                (self.geo.scale, self.geo.angle) = saved;
                Ok(f?.matrix())
            }
            _ => {
                let label = self.type_label(placement);
                self.warn(
                    &format!("xf:{label}"),
                    format!("placement kind {label} not supported; identity used"),
                );
                Ok(DMat4::IDENTITY)
            }
        }
    }
}

fn build_reps<'x, 'a>(c: &mut Ctx<'x, 'a>) -> R<RepTable> {
    let n = c.ex.entities.len();
    let mut order = Vec::new();
    let mut reps = HashMap::new();
    let mut in_reps = HashSet::new();
    for idx in 0..n {
        let Some(a) = c.rep_args(idx) else { continue };
        let items = a.refs(1)?;
        let context = a.opt_r(2)?;
        let mut geometry = false;
        for &it in &items {
            let h = c.head(it);
            if SOLID_TYPES.contains(&h)
                || matches!(
                    h,
                    "SHELL_BASED_SURFACE_MODEL"
                        | "CLOSED_SHELL"
                        | "OPEN_SHELL"
                        | "ORIENTED_CLOSED_SHELL"
                        | "ORIENTED_OPEN_SHELL"
                )
            {
                geometry = true;
                in_reps.insert(it);
            }
        }
        order.push(idx);
        reps.insert(
            idx,
            RepInfo {
                items,
                context,
                geometry,
            },
        );
    }
    Ok((order, reps, in_reps))
}

/// Parent → children links between representations.
fn build_links(
    c: &mut Ctx<'_, '_>,
    reps: &HashMap<usize, RepInfo>,
) -> R<HashMap<usize, Vec<Link>>> {
    let ex = c.ex;
    let n = ex.entities.len();
    let mut links: HashMap<usize, Vec<Link>> = HashMap::new();

    // Product definition → its shape representations (for CDSR direction).
    let mut pd_reps: HashMap<usize, Vec<usize>> = HashMap::new();
    for idx in 0..n {
        if c.head(idx) != "SHAPE_DEFINITION_REPRESENTATION" {
            continue;
        }
        let a = c.args(idx);
        let (Ok(Some(pds)), Ok(Some(rep))) = (a.opt_r(0), a.opt_r(1)) else {
            continue;
        };
        if let Ok(Some(pd)) = c.args(pds).opt_r(2) {
            pd_reps.entry(pd).or_default().push(rep);
        }
    }
    // Relationship → reversed (rep_2 is the child).
    let mut reversed: HashMap<usize, bool> = HashMap::new();
    for idx in 0..n {
        if c.head(idx) != "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION" {
            continue;
        }
        let a = c.args(idx);
        let (Ok(Some(rel)), Ok(Some(pds))) = (a.opt_r(0), a.opt_r(1)) else {
            continue;
        };
        let Ok(Some(nauo)) = c.args(pds).opt_r(2) else {
            continue;
        };
        let na = c.args(nauo);
        let (Ok(Some(parent_pd)), Ok(Some(child_pd))) = (na.opt_r(3), na.opt_r(4)) else {
            continue;
        };
        let Some((r1, r2)) = rel_reps(c, rel) else {
            continue;
        };
        let of = |pd: usize| pd_reps.get(&pd).map(|v| v.as_slice()).unwrap_or(&[]);
        let rev = of(child_pd).contains(&r2) || of(parent_pd).contains(&r1);
        reversed.insert(rel, rev);
    }

    for idx in 0..n {
        // Representation relationships (with or without a transformation).
        if rel_reps(c, idx).is_some() {
            let a = rel_args(c, idx).ok_or_else(|| c.unsupported(idx, "relationship"))?;
            let rep1 = a.r(2)?;
            let rep2 = a.r(3)?;
            if !reps.contains_key(&rep1) || !reps.contains_key(&rep2) {
                continue;
            }
            let transformation = if let Some(t) =
                c.part_args(idx, "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION")
            {
                Some(t.r(0)?)
            } else if c.head(idx) == "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION" {
                Some(a.r(4)?)
            } else {
                None
            };
            let (child, parent, xf) = match transformation {
                Some(t) => {
                    let rev = reversed.get(&idx).copied().unwrap_or(false);
                    let (child, parent) = if rev { (rep2, rep1) } else { (rep1, rep2) };
                    let xf = if c.head(t) == "ITEM_DEFINED_TRANSFORMATION" {
                        let ta = c.args(t);
                        let (i1, i2) = (ta.r(2)?, ta.r(3)?);
                        if rev {
                            Xf::Items {
                                child: i2,
                                parent: i1,
                            }
                        } else {
                            Xf::Items {
                                child: i1,
                                parent: i2,
                            }
                        }
                    } else {
                        let label = c.type_label(t);
                        c.warn(
                            &format!("xf:{label}"),
                            format!("transformation kind {label} not supported; identity used"),
                        );
                        Xf::Identity
                    };
                    (child, parent, xf)
                }
                None => {
                    // A plain link between a shape representation and the one
                    // holding its geometry: the geometry side is the child.
                    let g1 = c.is_geometry_rep_type(rep1) || reps[&rep1].geometry;
                    let g2 = c.is_geometry_rep_type(rep2) || reps[&rep2].geometry;
                    if g1 && !g2 {
                        (rep1, rep2, Xf::Identity)
                    } else {
                        (rep2, rep1, Xf::Identity)
                    }
                }
            };
            links.entry(parent).or_default().push(Link {
                child,
                xf,
                via: idx,
            });
        }
    }
    // Mapped items.
    let mut rep_ids: Vec<usize> = reps.keys().copied().collect();
    rep_ids.sort_unstable();
    for r in rep_ids {
        for &it in &reps[&r].items {
            if c.head(it) != "MAPPED_ITEM" {
                continue;
            }
            let a = c.args(it);
            let map = a.r(1)?;
            let target = a.r(2)?;
            let ma = c.expect_type(map, &["REPRESENTATION_MAP"], "a representation map")?;
            let origin = ma.r(0)?;
            let child = ma.r(1)?;
            if !reps.contains_key(&child) {
                return Err(ma.wrong("mapped representation is not a representation"));
            }
            links.entry(r).or_default().push(Link {
                child,
                xf: Xf::Items {
                    child: origin,
                    parent: target,
                },
                via: it,
            });
        }
    }
    Ok(links)
}

fn rel_args<'x, 'a>(c: &Ctx<'x, 'a>, idx: usize) -> Option<A<'x, 'a>> {
    let h = c.head(idx);
    if h.is_empty() {
        c.part_args(idx, "REPRESENTATION_RELATIONSHIP")
    } else if h.ends_with("REPRESENTATION_RELATIONSHIP")
        || h == "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION"
    {
        Some(c.args(idx))
    } else {
        None
    }
}

fn rel_reps(c: &Ctx<'_, '_>, idx: usize) -> Option<(usize, usize)> {
    let a = rel_args(c, idx)?;
    Some((a.opt_r(2).ok()??, a.opt_r(3).ok()??))
}

/// Errors if the representation graph has a cycle (iterative DFS).
fn check_acyclic(c: &Ctx<'_, '_>, order: &[usize], links: &HashMap<usize, Vec<Link>>) -> R<()> {
    // 0 unvisited, 1 on stack, 2 done
    let mut color: HashMap<usize, u8> = HashMap::new();
    for &root in order {
        if color.get(&root).copied().unwrap_or(0) != 0 {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        color.insert(root, 1);
        while let Some(&mut (node, ref mut next)) = stack.last_mut() {
            let kids = links.get(&node).map(|v| v.as_slice()).unwrap_or(&[]);
            if let Some(l) = kids.get(*next) {
                *next += 1;
                match color.get(&l.child).copied().unwrap_or(0) {
                    0 => {
                        color.insert(l.child, 1);
                        stack.push((l.child, 0));
                    }
                    1 => {
                        let id = |i: usize| c.ent(i).map(|e| e.id).unwrap_or(0);
                        let mut chain: Vec<String> = stack
                            .iter()
                            .skip_while(|(n, _)| *n != l.child)
                            .map(|(n, _)| format!("#{}", id(*n)))
                            .collect();
                        chain.push(format!("#{}", id(l.child)));
                        return Err(StepErrorKind::Cyclic {
                            place: place_of(c.ex, l.via),
                            chain: format!("assembly representations {}", chain.join(" -> ")),
                        });
                    }
                    _ => {}
                }
            } else {
                color.insert(node, 2);
                stack.pop();
            }
        }
    }
    Ok(())
}

struct Assembler<'x, 'a> {
    c: Ctx<'x, 'a>,
    reps: HashMap<usize, RepInfo>,
    links: HashMap<usize, Vec<Link>>,
    cache: HashMap<usize, Brep>,
    out: Brep,
    first_units: Option<Units>,
    units_seen: HashSet<String>,
}

impl<'x, 'a> Assembler<'x, 'a> {
    fn rep_units(&mut self, rep: usize) -> R<Units> {
        let ctx = self.reps.get(&rep).and_then(|r| r.context);
        self.c.context_units(ctx)
    }

    fn rep_brep(&mut self, rep: usize) -> R<&Brep> {
        if !self.cache.contains_key(&rep) {
            let u = self.rep_units(rep)?;
            let items = self
                .reps
                .get(&rep)
                .map(|r| r.items.clone())
                .unwrap_or_default();
            self.c.geo = Geo::new(&u);
            let mut any = false;
            for it in items {
                any |= self.c.item(it)?;
            }
            if any {
                if self.first_units.is_none() {
                    self.first_units = Some(u.clone());
                }
                self.units_seen.insert(u.name.clone());
            }
            let b = std::mem::replace(&mut self.c.geo, Geo::new(&Units::mm())).brep;
            self.cache.insert(rep, b);
        }
        Ok(&self.cache[&rep])
    }

    fn expand(&mut self, rep: usize, m: DMat4, depth: usize) -> R<()> {
        if depth > self.c.limits.max_depth {
            return Err(StepErrorKind::Limit {
                place: place_of(self.c.ex, rep),
                reason: format!("assembly nested deeper than {}", self.c.limits.max_depth),
            });
        }
        self.c.tick(1, rep)?;
        let identity = m == DMat4::IDENTITY;
        let b = self.rep_brep(rep)?;
        let coedges: usize = b.loops.iter().map(|l| l.coedges.len()).sum();
        let size =
            (b.vertices.len() + b.edges.len() + b.faces.len() + b.loops.len() + coedges) as u64;
        if !b.faces.is_empty() || !b.solids.is_empty() {
            self.c.tick(size, rep)?;
            if let Some(b) = self.cache.get(&rep) {
                append_transformed(&mut self.out, b, (!identity).then_some(&m));
            }
        }
        let kids = self.links.get(&rep).cloned().unwrap_or_default();
        for l in kids {
            let local = match l.xf {
                Xf::Identity => DMat4::IDENTITY,
                Xf::Items { child, parent } => {
                    let cu = self.rep_units(l.child)?;
                    let pu = self.rep_units(rep)?;
                    let mc = self.c.matrix_of(child, &cu)?;
                    let mp = self.c.matrix_of(parent, &pu)?;
                    mp * mc.inverse()
                }
            };
            self.expand(l.child, m * local, depth + 1)?;
        }
        Ok(())
    }
}

/// Appends `b` to `out`, transforming only the appended part.
fn append_transformed(out: &mut Brep, b: &Brep, m: Option<&DMat4>) {
    let (v0, e0, f0) = (out.vertices.len(), out.edges.len(), out.faces.len());
    out.append(b);
    if let Some(m) = m {
        for v in &mut out.vertices[v0..] {
            v.point = m.transform_point3(v.point);
        }
        for e in &mut out.edges[e0..] {
            e.curve.transform(m);
        }
        for f in &mut out.faces[f0..] {
            f.surface.transform(m);
        }
    }
}

pub(crate) fn build(ex: &Exchange<'_>, limits: &Limits) -> R<Built> {
    let mut c = Ctx {
        ex,
        limits: *limits,
        work: 0,
        warnings: Vec::new(),
        warned: HashSet::new(),
        active: vec![false; ex.entities.len()],
        path: Vec::new(),
        geo: Geo::new(&Units::mm()),
        unit_cache: HashMap::new(),
        open_shells: Vec::new(),
    };
    c.tick(ex.entities.len() as u64, 0)?;
    let (order, reps, in_reps) = build_reps(&mut c)?;
    let links = build_links(&mut c, &reps)?;
    check_acyclic(&c, &order, &links)?;
    let mut has_parent: HashSet<usize> = HashSet::new();
    for ls in links.values() {
        for l in ls {
            has_parent.insert(l.child);
        }
    }
    let mut asm = Assembler {
        c,
        reps,
        links,
        cache: HashMap::new(),
        out: Brep::new(),
        first_units: None,
        units_seen: HashSet::new(),
    };
    for &r in &order {
        if !has_parent.contains(&r) {
            asm.expand(r, DMat4::IDENTITY, 0)?;
        }
    }
    // Solids and surface models that no representation holds.
    let mut loose = Vec::new();
    for idx in 0..ex.entities.len() {
        let h = asm.c.head(idx);
        if (SOLID_TYPES.contains(&h) || h == "SHELL_BASED_SURFACE_MODEL") && !in_reps.contains(&idx)
        {
            loose.push(idx);
        }
    }
    if !loose.is_empty() {
        // Use the first length unit any context declares.
        let mut u = None;
        for idx in 0..ex.entities.len() {
            if asm.c.has_part(idx, "GLOBAL_UNIT_ASSIGNED_CONTEXT") {
                let cu = asm.c.context_units(Some(idx))?;
                if cu.declared {
                    u = Some(cu);
                    break;
                }
            }
        }
        let u = u.unwrap_or_else(Units::mm);
        asm.c.geo = Geo::new(&u);
        for idx in loose {
            asm.c.item(idx)?;
        }
        let b = std::mem::replace(&mut asm.c.geo, Geo::new(&Units::mm())).brep;
        asm.out.append(&b);
        if asm.first_units.is_none() {
            asm.first_units = Some(u.clone());
        }
        asm.units_seen.insert(u.name);
    }
    let Assembler {
        mut c,
        out,
        first_units,
        units_seen,
        ..
    } = asm;
    if out.solids.is_empty() && out.shells.is_empty() {
        let tess = ex.entities.iter().any(|e| {
            ex.parts_of(e).iter().any(|p| {
                let n = ex.name(p.name);
                n.starts_with("TESSELLATED")
                    || n.starts_with("TRIANGULATED")
                    || n.starts_with("COMPLEX_TRIANGULATED")
            })
        });
        let reason = if tess {
            "tessellated geometry only"
        } else {
            "no MANIFOLD_SOLID_BREP, BREP_WITH_VOIDS or shell found"
        };
        return Err(StepErrorKind::NoSolid {
            reason: reason.into(),
        });
    }
    // A part that is not a closed solid must not be planned as one.
    if out.solids.is_empty() {
        if let Some(first) = c.open_shells.first() {
            let reason = match (first, c.open_shells.len()) {
                (e, 1) => e.to_string(),
                (e, n) => format!("{e}; and {} more open shell(s)", n - 1),
            };
            return Err(StepErrorKind::NoSolid { reason });
        }
        c.warnings.push(format!(
            "no solid in this file; {} closed shell(s) read as surface models",
            out.shells.len()
        ));
    } else {
        for e in &c.open_shells {
            c.warnings.push(format!(
                "besides the solids, a surface that is not closed: {e}"
            ));
        }
    }
    let units = first_units.unwrap_or_else(Units::mm);
    if !units.declared {
        c.warnings
            .push("no length unit declared; millimetres assumed".into());
    }
    if units_seen.len() > 1 {
        let mut v: Vec<String> = units_seen.into_iter().collect();
        v.sort();
        c.warnings.push(format!(
            "representations use different length units ({}); all converted to mm",
            v.join(", ")
        ));
    }
    Ok(Built {
        brep: out,
        units: units.name,
        warnings: c.warnings,
    })
}
