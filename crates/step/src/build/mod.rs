//! From parsed entities to a [`Brep`] in millimetres: topology, geometry,
//! units and assemblies.

mod args;
mod assembly;
mod bspline;
mod curves;
mod points;
mod representations;
mod shells;
mod surfaces;
mod topology;
mod units;
mod walk;

use std::collections::{HashMap, HashSet};

use glam::DMat4;
use thinplan_brep::Brep;

use crate::p21::Exchange;
use crate::{Limits, StepErrorKind};

use assembly::Assembler;
use representations::{build_links, build_reps, check_acyclic};
use units::Units;
use walk::Ctx;

type R<T> = Result<T, StepErrorKind>;

pub(crate) struct Built {
    pub brep: Brep,
    pub units: String,
    pub warnings: Vec<String>,
}

/// Builds the B-rep of every solid and surface model, placed as the
/// assemblies place them, in millimetres.
pub(crate) fn build(ex: &Exchange<'_>, limits: &Limits) -> R<Built> {
    let mut c = Ctx::new(ex, limits);
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
    asm.add_unheld_items(&in_reps)?;
    let Assembler {
        mut c,
        out,
        first_units,
        units_seen,
        ..
    } = asm;
    if out.solids.is_empty() && out.shells.is_empty() {
        return Err(no_solid(ex));
    }
    open_shells_verdict(&mut c, &out)?;
    let units = first_units.unwrap_or_else(Units::mm);
    unit_warnings(&mut c.warnings, &units, units_seen);
    Ok(Built {
        brep: out,
        units: units.name,
        warnings: c.warnings,
    })
}

/// Why a file with neither solid nor shell gave nothing.
fn no_solid(ex: &Exchange<'_>) -> StepErrorKind {
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
    StepErrorKind::NoSolid {
        reason: reason.into(),
    }
}

/// A part that is not a closed solid must not be planned as one: without a
/// solid, an open shell refuses the file; beside solids it is a warning.
fn open_shells_verdict(c: &mut Ctx<'_, '_>, out: &Brep) -> R<()> {
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
    Ok(())
}

/// Warns of an undeclared length unit, and of representations in
/// different ones.
fn unit_warnings(warnings: &mut Vec<String>, units: &Units, units_seen: HashSet<String>) {
    if !units.declared {
        warnings.push("no length unit declared; millimetres assumed".into());
    }
    if units_seen.len() > 1 {
        let mut v: Vec<String> = units_seen.into_iter().collect();
        v.sort();
        warnings.push(format!(
            "representations use different length units ({}); all converted to mm",
            v.join(", ")
        ));
    }
}
