//! The inspector: the selection's attributes, commands that highlight its
//! relations, why it is as it is (provenance), and its editor.

use eframe::egui::{self, Color32};
use thinplan_plan::{Operation, Plan, Region3};

use crate::conditions;
use crate::relations;
use crate::state::{AppState, Entity};

use super::actions::Act;
use super::editor::editor;
use super::{Forms, ThinplanApp};

impl ThinplanApp {
    pub(super) fn inspector(&mut self, ui: &mut egui::Ui) {
        let Some(sel) = self.state.selection else {
            ui.label("Select something in the tree, the 3D view or the network.");
            return;
        };
        self.refill_edit_forms();
        let mut acts = Vec::new();
        let ThinplanApp { state, forms, .. } = self;
        let Some(plan) = state.plan() else { return };
        let plan: &Plan = plan;
        ui.heading(format!("Inspector: {}", relations::name(plan, sel)));
        attributes(ui, state, forms, plan, sel);
        ui.separator();
        selection_commands(ui, state, plan, sel, &mut acts);
        provenance(ui, plan, sel);
        ui.separator();
        editor(ui, forms, plan, sel, &mut acts);
        if let Some(r) = &state.refusal {
            ui.colored_label(Color32::from_rgb(255, 110, 90), r);
        }
        for a in acts {
            self.apply(a);
        }
    }
}

/// The selection's attributes, one row each.
fn attributes(ui: &mut egui::Ui, state: &AppState, forms: &Forms, plan: &Plan, sel: Entity) {
    egui::Grid::new("attributes")
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            let mut row = |k: &str, v: String| {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            };
            match sel {
                Entity::Part => {
                    row("source", plan.part.source.clone());
                    row("format", format!("{:?}", plan.part.format));
                    row("faces", plan.part.summary.faces.to_string());
                    let b = plan.part.summary.bbox;
                    row(
                        "size mm",
                        format!("{:.1} × {:.1} × {:.1}", b[0], b[1], b[2]),
                    );
                    row("volume mm³", format!("{:.0}", plan.part.summary.volume));
                    row(
                        "sha256",
                        plan.part.sha256.chars().take(16).collect::<String>() + "…",
                    );
                }
                Entity::Setup => {
                    let s = &plan.setup;
                    row("up", format!("{:.3}, {:.3}, {:.3}", s.up.x, s.up.y, s.up.z));
                    row("machine", s.machine.clone());
                    row("tools", s.tool_set.clone());
                    row("material", s.material.clone());
                }
                Entity::Stiffness(id) => {
                    if let Some(f) = relations::sf(plan, id) {
                        row("kind", relations::kind_name(f.kind).into());
                        row("role", f.role.map_or("—".into(), |r| format!("{r:?}")));
                        row(
                            "thickness mm",
                            f.thickness.map_or("—".into(), |t| format!("{t:.3}")),
                        );
                        row("height mm", format!("{:.3}", f.height));
                        row("length mm", format!("{:.3}", f.length));
                        row("faces", format!("{:?}", f.faces));
                        row(
                            "axis",
                            format!("{:.3}, {:.3}, {:.3}", f.axis.x, f.axis.y, f.axis.z),
                        );
                    }
                }
                Entity::Machining(id) => {
                    if let Some(f) = relations::mf(plan, id) {
                        row("owner", f.owner.to_string());
                        row(
                            "z range mm",
                            format!("{:.3} – {:.3}", f.shape.z_min, f.shape.z_max),
                        );
                        row(
                            "profile vertices",
                            f.shape.region.outer.vertices.len().to_string(),
                        );
                        row("bottom", format!("{:?}", f.bottom_adjacency));
                    }
                }
                Entity::Operation(id) => {
                    if let Some(o) = plan.operations.iter().find(|o| o.id == id) {
                        operation_rows(&mut row, state, forms, plan, o);
                    }
                }
            }
        });
}

/// An operation's attributes: its tool and conditions beside what the
/// material allows, and the values its method computed.
fn operation_rows(
    row: &mut impl FnMut(&str, String),
    state: &AppState,
    forms: &Forms,
    plan: &Plan,
    o: &Operation,
) {
    row("feature", o.feature.to_string());
    row("method", o.method.clone());
    row("tool", o.tool.clone());
    row("spindle rpm", format!("{:.0}", o.spindle_rpm));
    let limits = state
        .knowledge()
        .and_then(|k| conditions::limits(plan, k, o).ok());
    let flutes = limits.as_ref().and_then(|l| l.flutes);
    let cutting = limits.as_ref().and_then(|l| l.cutting.clone());
    if let Some(d) = limits.as_ref().and_then(|l| l.tool_diameter) {
        let mut v = format!("{:.0}", conditions::cutting_speed(d, o.spindle_rpm));
        if let Some(c) = &cutting {
            v.push_str(&format!("  (material: {:.0})", c.cutting_speed));
        }
        row("cutting speed m/min", v);
    }
    for &(r, lo, hi) in &forms.feed_ranges {
        let mut v = if lo == hi {
            format!("{lo:.0}")
        } else {
            format!("{lo:.0} – {hi:.0}")
        };
        if let (Some(z), Region3::Boundary | Region3::FullCut | Region3::Rest) = (flutes, r) {
            let fz = conditions::feed_per_tooth(hi, o.spindle_rpm, z);
            v.push_str(&format!("  ({fz:.4} mm/tooth)"));
        }
        row(&format!("{} feed mm/min", conditions::region_name(r)), v);
    }
    if let Some(c) = &cutting {
        row(
            "material feed per tooth mm",
            format!(
                "roughing {:.4}, finishing {:.4}",
                c.feed_per_tooth_roughing, c.feed_per_tooth_finishing
            ),
        );
    }
    let pv = |k: &str| o.provenance.values.get(k).copied();
    for (k, name) in [
        ("stepover_rest_mm", "stepover rest mm"),
        ("stepover_boundary_mm", "stepover boundary mm"),
        ("depth_of_cut_mm", "depth of cut mm"),
        ("layers", "layers"),
        ("time_s", "time s"),
    ] {
        if let Some(v) = pv(k) {
            row(name, format!("{v:.3}"));
        }
    }
    row("moves", o.moves.len().to_string());
}

/// Commands that highlight the selection's relations, its owner, and the
/// highlighted entities as links.
fn selection_commands(
    ui: &mut egui::Ui,
    state: &AppState,
    plan: &Plan,
    sel: Entity,
    acts: &mut Vec<Act>,
) {
    ui.horizontal_wrapped(|ui| {
        let mut hl = None;
        if ui.button("predecessors").clicked() {
            hl = Some(relations::neighbours(plan, sel, false, false));
        }
        if ui.button("all predecessors").clicked() {
            hl = Some(relations::neighbours(plan, sel, false, true));
        }
        if ui.button("successors").clicked() {
            hl = Some(relations::neighbours(plan, sel, true, false));
        }
        if ui.button("all successors").clicked() {
            hl = Some(relations::neighbours(plan, sel, true, true));
        }
        if ui.button("together").clicked() {
            hl = Some(relations::together(plan, sel));
        }
        if ui.button("owned").clicked() {
            hl = Some(relations::owned(plan, sel));
        }
        if let Some(o) = relations::owner(plan, sel) {
            if ui.button("owner").clicked() {
                acts.push(Act::Select(Some(o)));
            }
        }
        if let Some(h) = hl {
            acts.push(Act::Highlight(h));
        }
    });
    if !state.highlighted.is_empty() {
        ui.horizontal_wrapped(|ui| {
            for e in &state.highlighted {
                if ui.link(e.to_string()).clicked() {
                    acts.push(Act::Select(Some(*e)));
                }
            }
        });
    }
}

/// Why the selection is as it is: the rule and values that made it.
fn provenance(ui: &mut egui::Ui, plan: &Plan, sel: Entity) {
    egui::CollapsingHeader::new("why? (provenance)")
        .default_open(true)
        .show(ui, |ui| match relations::provenance(plan, sel) {
            Some(p) => {
                ui.label(format!("{:?}: {}", p.source, p.rule));
                for (k, v) in &p.values {
                    ui.label(format!("  {k} = {v}"));
                }
                if !p.note.is_empty() {
                    ui.label(&p.note);
                }
            }
            None => {
                ui.label(format!("imported from {}", plan.part.source));
            }
        });
}
