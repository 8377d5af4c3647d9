//! Assemblies: each representation's B-rep built once and placed, through
//! the links, as many times as the assembly holds it.

use std::collections::{HashMap, HashSet};

use glam::DMat4;
use thinplan_brep::Brep;

use crate::StepErrorKind;

use super::args::place_of;
use super::representations::{Link, RepInfo, Xf};
use super::shells::SOLID_TYPES;
use super::topology::Geo;
use super::units::Units;
use super::walk::Ctx;
use super::R;

impl<'x, 'a> Ctx<'x, 'a> {
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

pub(super) struct Assembler<'x, 'a> {
    pub(super) c: Ctx<'x, 'a>,
    pub(super) reps: HashMap<usize, RepInfo>,
    pub(super) links: HashMap<usize, Vec<Link>>,
    pub(super) cache: HashMap<usize, Brep>,
    pub(super) out: Brep,
    pub(super) first_units: Option<Units>,
    pub(super) units_seen: HashSet<String>,
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

    pub(super) fn expand(&mut self, rep: usize, m: DMat4, depth: usize) -> R<()> {
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

    /// Solids and surface models that no representation holds, in the
    /// first length unit any context declares.
    pub(super) fn add_unheld_items(&mut self, in_reps: &HashSet<usize>) -> R<()> {
        let mut loose = Vec::new();
        for idx in 0..self.c.ex.entities.len() {
            let h = self.c.head(idx);
            if (SOLID_TYPES.contains(&h) || h == "SHELL_BASED_SURFACE_MODEL")
                && !in_reps.contains(&idx)
            {
                loose.push(idx);
            }
        }
        if !loose.is_empty() {
            // Use the first length unit any context declares.
            let mut u = None;
            for idx in 0..self.c.ex.entities.len() {
                if self.c.has_part(idx, "GLOBAL_UNIT_ASSIGNED_CONTEXT") {
                    let cu = self.c.context_units(Some(idx))?;
                    if cu.declared {
                        u = Some(cu);
                        break;
                    }
                }
            }
            let u = u.unwrap_or_else(Units::mm);
            self.c.geo = Geo::new(&u);
            for idx in loose {
                self.c.item(idx)?;
            }
            let b = std::mem::replace(&mut self.c.geo, Geo::new(&Units::mm())).brep;
            self.out.append(&b);
            if self.first_units.is_none() {
                self.first_units = Some(u.clone());
            }
            self.units_seen.insert(u.name);
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
