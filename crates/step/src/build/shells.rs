//! Shells, solids and surface models, and the closed-solid and
//! orientation checks run on each shell.

use std::collections::HashSet;

use thinplan_brep::{EdgeId, Shell, Solid};

use crate::check::{self, Expect};
use crate::StepErrorKind;

use super::args::place_of;
use super::topology::EdgeSrc;
use super::walk::Ctx;
use super::R;

/// The entities read as one solid each.
pub(super) const SOLID_TYPES: [&str; 3] =
    ["MANIFOLD_SOLID_BREP", "BREP_WITH_VOIDS", "FACETED_BREP"];

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

impl<'x, 'a> Ctx<'x, 'a> {
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
    pub(super) fn item(&mut self, idx: usize) -> R<bool> {
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
}
