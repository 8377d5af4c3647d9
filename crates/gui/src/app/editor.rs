//! The selection's editor: thickness, role, sequence constraints and
//! connections of a stiffness feature; resize, split and merge of a
//! machining feature; spindle and feeds of an operation. Edits become
//! actions (`Act`), applied after drawing.

use eframe::egui::{self, RichText};
use thinplan_plan::{
    ConnectionKind, ConstraintKind, MachiningFeatureId, OperationId, Plan, StiffnessFeatureId,
    WallRole,
};

use crate::conditions;
use crate::relations;
use crate::state::{connection_word, kind_word, Entity};

use super::actions::Act;
use super::drawing;
use super::{Forms, ThinplanApp};

/// How the selected stiffness feature stands to the one it is connected to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ConnectAs {
    /// The selected feature is the base; the other is its leaf.
    #[default]
    Base,
    Leaf,
    Crossing,
}

impl ThinplanApp {
    /// Fills the editor's fields from the selection once per selection and
    /// plan generation, so that what is typed is not overwritten each frame.
    pub(super) fn refill_edit_forms(&mut self) {
        let Some(sel) = self.state.selection else {
            return;
        };
        let key = (sel, self.state.plan_generation);
        if self.forms.filled_for == Some(key) {
            return;
        }
        let Some(plan) = self.state.plan() else {
            return;
        };
        match sel {
            Entity::Stiffness(id) => {
                if let Some(f) = relations::sf(plan, id) {
                    self.forms.thickness = f.thickness.unwrap_or(0.0);
                }
                self.forms.draw_z = drawing::plan_z_range(plan, id);
            }
            Entity::Machining(id) => {
                if let Some(f) = relations::mf(plan, id) {
                    self.forms.z_min = f.shape.z_min;
                    self.forms.z_max = f.shape.z_max;
                    self.forms.split_z = 0.5 * (f.shape.z_min + f.shape.z_max);
                    // A line across the middle of the profile, along its y.
                    let (lo, hi) = profile_box(&f.shape.region.outer);
                    let cx = 0.5 * (lo.x + hi.x);
                    self.forms.split_line = [cx, lo.y - 1.0, cx, hi.y + 1.0];
                    self.forms.merge_with = None;
                    let (a, b) = drawing::plan_z_range(plan, f.owner);
                    self.forms.draw_z = (a, b);
                }
            }
            Entity::Operation(id) => {
                if let Some(o) = plan.operations.iter().find(|o| o.id == id) {
                    self.forms.spindle = o.spindle_rpm;
                    self.forms.feed_ranges = conditions::feeds(o);
                    self.forms.feeds = self
                        .forms
                        .feed_ranges
                        .iter()
                        .map(|&(r, lo, _)| (r, lo))
                        .collect();
                }
            }
            _ => {}
        }
        self.forms.filled_for = Some(key);
    }
}

/// The bounding box of a loop's vertices.
fn profile_box(l: &thinplan_plan::ProfileLoop) -> (glam::DVec2, glam::DVec2) {
    let mut lo = glam::DVec2::splat(f64::INFINITY);
    let mut hi = glam::DVec2::splat(f64::NEG_INFINITY);
    for v in &l.vertices {
        lo = lo.min(glam::DVec2::new(v.x, v.y));
        hi = hi.max(glam::DVec2::new(v.x, v.y));
    }
    if !lo.is_finite() {
        return (glam::DVec2::ZERO, glam::DVec2::ZERO);
    }
    (lo, hi)
}

/// The editor of the selection, if it can be edited.
pub(super) fn editor(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    sel: Entity,
    acts: &mut Vec<Act>,
) {
    match sel {
        Entity::Stiffness(id) => stiffness_editor(ui, forms, plan, id, acts),
        Entity::Machining(id) => machining_editor(ui, forms, plan, id, acts),
        Entity::Operation(id) => operation_editor(ui, forms, id, acts),
        _ => {}
    }
}

fn stiffness_editor(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    id: StiffnessFeatureId,
    acts: &mut Vec<Act>,
) {
    ui.label(RichText::new("Edit").strong());
    ui.horizontal(|ui| {
        ui.label("thickness");
        ui.add(
            egui::DragValue::new(&mut forms.thickness)
                .speed(0.01)
                .range(0.001..=1e4),
        );
        if ui.button("Set thickness").clicked() {
            acts.push(Act::Thickness(id, forms.thickness));
        }
    });
    let role = relations::sf(plan, id).and_then(|f| f.role);
    ui.horizontal(|ui| {
        ui.label("role");
        for r in [
            None,
            Some(WallRole::Web),
            Some(WallRole::Rib),
            Some(WallRole::Flange),
        ] {
            let name = r.map_or("none".to_string(), |r| format!("{r:?}").to_lowercase());
            if ui.selectable_label(role == r, name).clicked() && role != r {
                acts.push(Act::Role(id, r));
            }
        }
    });
    drawing::draw_section(ui, forms, plan, id, acts);
    connections_section(ui, forms, plan, id, acts);
    constraints_section(ui, forms, plan, id, acts);
}

/// The sequence constraints on stiffness feature `id`, each removable, and
/// a row to add one.
fn constraints_section(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    id: StiffnessFeatureId,
    acts: &mut Vec<Act>,
) {
    ui.label(RichText::new("Sequence constraints").strong());
    let mut remove = None;
    for (i, c) in plan.stiffness_constraints.iter().enumerate() {
        if c.first == id || c.second == id {
            ui.horizontal(|ui| {
                ui.label(format!(
                    "{} {} {}  ({})",
                    c.first,
                    kind_word(c.kind),
                    c.second,
                    c.provenance.rule
                ));
                if ui.small_button("remove").clicked() {
                    remove = Some(i);
                }
            });
        }
    }
    if let Some(i) = remove {
        acts.push(Act::RemoveConstraint(i));
    }
    ui.horizontal(|ui| {
        ui.label(format!("{id}"));
        let kind = forms.kind.get_or_insert(ConstraintKind::Before);
        ui.selectable_value(kind, ConstraintKind::Before, "before");
        ui.selectable_value(kind, ConstraintKind::Simultaneous, "with");
        let others: Vec<StiffnessFeatureId> = plan
            .stiffness_features
            .iter()
            .map(|f| f.id)
            .filter(|o| *o != id)
            .collect();
        if forms.other.is_none_or(|o| !others.contains(&o)) {
            forms.other = others.first().copied();
        }
        egui::ComboBox::from_id_salt("other feature")
            .selected_text(forms.other.map_or(String::new(), |o| o.to_string()))
            .show_ui(ui, |ui| {
                for o in &others {
                    ui.selectable_value(&mut forms.other, Some(*o), o.to_string());
                }
            });
        if ui.button("Add constraint").clicked() {
            if let Some(o) = forms.other {
                let k = forms.kind.unwrap_or(ConstraintKind::Before);
                acts.push(Act::AddConstraint(id, o, k));
            }
        }
    });
}

/// The connections of stiffness feature `id`, each removable, and a row to
/// connect it to another one.
fn connections_section(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    id: StiffnessFeatureId,
    acts: &mut Vec<Act>,
) {
    // Closed by default: a web may carry dozens of features.
    let n = plan
        .connections
        .iter()
        .filter(|c| c.base == id || c.leaf == id)
        .count();
    egui::CollapsingHeader::new(format!("Connections of {id} ({n})"))
        .id_salt("connections")
        .show(ui, |ui| {
            for c in plan
                .connections
                .iter()
                .filter(|c| c.base == id || c.leaf == id)
            {
                let other = if c.base == id { c.leaf } else { c.base };
                ui.horizontal(|ui| {
                    ui.label(format!(
                        "{} {} {}  ({})",
                        c.base,
                        connection_word(c.kind),
                        c.leaf,
                        c.provenance.rule
                    ));
                    if ui.small_button(format!("disconnect {other}")).clicked() {
                        acts.push(Act::Disconnect(id, other));
                    }
                });
            }
            ui.horizontal(|ui| {
                ui.label(format!("{id}"));
                let a = &mut forms.connect_as;
                ui.selectable_value(a, ConnectAs::Base, "carries");
                ui.selectable_value(a, ConnectAs::Leaf, "is carried by");
                ui.selectable_value(a, ConnectAs::Crossing, "crosses");
                let others = || {
                    plan.stiffness_features
                        .iter()
                        .map(|f| f.id)
                        .filter(move |o| *o != id)
                };
                if forms
                    .connect_to
                    .is_none_or(|o| o == id || relations::sf(plan, o).is_none())
                {
                    forms.connect_to = others().next();
                }
                egui::ComboBox::from_id_salt("connect to")
                    .selected_text(forms.connect_to.map_or("—".into(), |o| o.to_string()))
                    .show_ui(ui, |ui| {
                        for o in others() {
                            ui.selectable_value(
                                &mut forms.connect_to,
                                Some(o),
                                format!("connect to {o}"),
                            );
                        }
                    });
                if ui.button("Add connection").clicked() {
                    if let Some(o) = forms.connect_to {
                        acts.push(match forms.connect_as {
                            ConnectAs::Base => Act::Connect(id, o, ConnectionKind::BaseLeaf),
                            ConnectAs::Leaf => Act::Connect(o, id, ConnectionKind::BaseLeaf),
                            ConnectAs::Crossing => Act::Connect(id, o, ConnectionKind::Crossing),
                        });
                    }
                }
            });
        });
}

fn machining_editor(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    id: MachiningFeatureId,
    acts: &mut Vec<Act>,
) {
    ui.label(RichText::new("Edit").strong());
    ui.horizontal(|ui| {
        ui.label("z from");
        ui.add(egui::DragValue::new(&mut forms.z_min).speed(0.05));
        ui.label("to");
        ui.add(egui::DragValue::new(&mut forms.z_max).speed(0.05));
        if ui.button("Resize").clicked() {
            acts.push(Act::Resize(id, forms.z_min, forms.z_max));
        }
    });
    ui.horizontal(|ui| {
        ui.label("at z");
        ui.add(egui::DragValue::new(&mut forms.split_z).speed(0.05));
        if ui.button("Split at height").clicked() {
            acts.push(Act::SplitAt(id, forms.split_z));
        }
    });
    ui.horizontal(|ui| {
        ui.label("line");
        for v in &mut forms.split_line {
            ui.add(egui::DragValue::new(v).speed(0.1).max_decimals(3));
        }
    });
    if ui.button("Split by line").clicked() {
        let l = forms.split_line;
        acts.push(Act::SplitLine(
            id,
            glam::DVec2::new(l[0], l[1]),
            glam::DVec2::new(l[2], l[3]),
        ));
    }
    let owner = relations::mf(plan, id).map(|f| f.owner);
    // The other features of the owner, listed only while the list is
    // open (a wall may own thousands).
    let same_owner = || {
        plan.machining_features
            .iter()
            .filter(move |f| Some(f.owner) == owner && f.id != id)
            .map(|f| f.id)
    };
    let valid = |m: thinplan_plan::MachiningFeatureId| {
        m != id && relations::mf(plan, m).is_some_and(|g| Some(g.owner) == owner)
    };
    if forms.merge_with.is_none_or(|m| !valid(m)) {
        forms.merge_with = same_owner().next();
    }
    ui.horizontal(|ui| {
        ui.label("merge with");
        egui::ComboBox::from_id_salt("merge with")
            .selected_text(forms.merge_with.map_or("—".into(), |m| m.to_string()))
            .show_ui(ui, |ui| {
                for m in same_owner() {
                    ui.selectable_value(&mut forms.merge_with, Some(m), m.to_string());
                }
            });
        if ui
            .add_enabled(forms.merge_with.is_some(), egui::Button::new("Merge"))
            .clicked()
        {
            if let Some(m) = forms.merge_with {
                acts.push(Act::Merge(id, m));
            }
        }
    });
    if let Some(o) = owner {
        drawing::draw_section(ui, forms, plan, o, acts);
    }
}

fn operation_editor(ui: &mut egui::Ui, forms: &mut Forms, id: OperationId, acts: &mut Vec<Act>) {
    ui.label(RichText::new("Edit").strong());
    ui.horizontal(|ui| {
        ui.label("spindle rpm");
        ui.add(
            egui::DragValue::new(&mut forms.spindle)
                .speed(10.0)
                .range(1.0..=1e6),
        );
        if ui.button("Set spindle").clicked() {
            acts.push(Act::Spindle(id, forms.spindle));
        }
    });
    for (r, feed) in &mut forms.feeds {
        let name = conditions::region_name(*r);
        ui.horizontal(|ui| {
            ui.label(format!("{name} feed mm/min"));
            ui.add(egui::DragValue::new(feed).speed(10.0).range(0.0..=1e6));
            if ui.button(format!("Set {name} feed")).clicked() {
                acts.push(Act::Feed(id, *r, *feed));
            }
        });
    }
    ui.label(
        RichText::new(
            "Stepover and depth of cut shape the tool path: stage 7 builds it for the \
             whole machining feature from its method in knowledge/methods.ron and cannot \
             rebuild one operation from the plan. Change the method and reload the \
             knowledge (the stages run again).",
        )
        .weak(),
    );
}
