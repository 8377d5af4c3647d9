//! The walk over the entity graph: the state of one build, typed lookup
//! of entities, errors that name them, the cycle and depth guards, the
//! work budget and the warnings.

use std::collections::{HashMap, HashSet};

use crate::p21::{Entity, Exchange, Part};
use crate::{Limits, StepErrorKind};

use super::args::{place_of, A};
use super::topology::Geo;
use super::units::Units;
use super::R;

/// The state of one build: the exchange, the budget, the warnings, the
/// cycle guard, the representation being built and the units read.
pub(super) struct Ctx<'x, 'a> {
    pub(super) ex: &'x Exchange<'a>,
    pub(super) limits: Limits,
    work: u64,
    pub(super) warnings: Vec<String>,
    warned: HashSet<String>,
    /// Entities whose resolution is in progress (cycle detection).
    active: Vec<bool>,
    /// The entities being resolved, outermost first.
    path: Vec<usize>,
    pub(super) geo: Geo,
    pub(super) unit_cache: HashMap<usize, Units>,
    /// Why each shell outside a solid is not closed (file order).
    pub(super) open_shells: Vec<StepErrorKind>,
}

impl<'x, 'a> Ctx<'x, 'a> {
    pub(super) fn new(ex: &'x Exchange<'a>, limits: &Limits) -> Ctx<'x, 'a> {
        Ctx {
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
        }
    }

    pub(super) fn warn(&mut self, key: &str, msg: String) {
        if self.warned.insert(key.to_string()) {
            self.warnings.push(msg);
        }
    }

    pub(super) fn tick(&mut self, n: u64, idx: usize) -> R<()> {
        self.work = self.work.saturating_add(n);
        if self.work > self.limits.max_work {
            return Err(StepErrorKind::Limit {
                place: place_of(self.ex, idx),
                reason: format!("more than {} units of work (limit)", self.limits.max_work),
            });
        }
        Ok(())
    }

    pub(super) fn ent(&self, idx: usize) -> Option<&'x Entity> {
        self.ex.entities.get(idx)
    }

    /// The type name of a simple entity, or "" for a complex one.
    pub(super) fn head(&self, idx: usize) -> &'x str {
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
    pub(super) fn type_label(&self, idx: usize) -> String {
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

    pub(super) fn has_part(&self, idx: usize, name: &str) -> bool {
        self.part(idx, name).is_some()
    }

    /// Arguments of the simple entity at `idx` (or its part named like its head).
    pub(super) fn args(&self, idx: usize) -> A<'x, 'a> {
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
    pub(super) fn part_args(&self, idx: usize, name: &'x str) -> Option<A<'x, 'a>> {
        let ex: &'x Exchange<'a> = self.ex;
        self.part(idx, name).map(|p| A {
            ex,
            idx,
            ty: name,
            vals: ex.args(p),
        })
    }

    pub(super) fn expect_type(&self, idx: usize, types: &[&str], role: &str) -> R<A<'x, 'a>> {
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
    pub(super) fn bad_kind(&self, idx: usize, types: &[&str], role: &str) -> StepErrorKind {
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

    pub(super) fn unsupported(&self, idx: usize, reason: impl Into<String>) -> StepErrorKind {
        StepErrorKind::Unsupported {
            place: place_of(self.ex, idx),
            entity: self.type_label(idx),
            reason: reason.into(),
        }
    }

    /// Marks `idx` as being resolved; errors on a cycle or too deep a chain.
    pub(super) fn enter(&mut self, idx: usize, from: usize) -> R<()> {
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

    pub(super) fn leave(&mut self, idx: usize) {
        if let Some(a) = self.active.get_mut(idx) {
            *a = false;
        }
        self.path.pop();
    }
}
