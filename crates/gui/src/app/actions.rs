//! What the panels ask of the state, and its application after drawing.

use std::collections::BTreeSet;

use thinplan_plan::{ConnectionKind, ConstraintKind, Region3, StiffnessFeatureId, WallRole};

use crate::state::Entity;

use super::ThinplanApp;

/// What a panel asked for, applied after drawing (the plan is borrowed
/// while drawing, never copied).
pub(super) enum Act {
    Select(Option<Entity>),
    Highlight(BTreeSet<Entity>),
    Thickness(StiffnessFeatureId, f64),
    Role(StiffnessFeatureId, Option<WallRole>),
    AddConstraint(StiffnessFeatureId, StiffnessFeatureId, ConstraintKind),
    RemoveConstraint(usize),
    Resize(thinplan_plan::MachiningFeatureId, f64, f64),
    SplitAt(thinplan_plan::MachiningFeatureId, f64),
    SplitLine(thinplan_plan::MachiningFeatureId, glam::DVec2, glam::DVec2),
    Merge(
        thinplan_plan::MachiningFeatureId,
        thinplan_plan::MachiningFeatureId,
    ),
    Draw(StiffnessFeatureId, Vec<glam::DVec2>, f64, f64),
    Spindle(thinplan_plan::OperationId, f64),
    Feed(thinplan_plan::OperationId, Region3, f64),
    Connect(StiffnessFeatureId, StiffnessFeatureId, ConnectionKind),
    Disconnect(StiffnessFeatureId, StiffnessFeatureId),
}

impl ThinplanApp {
    /// Applies what a panel asked for, once the frame no longer borrows the
    /// plan.
    pub(super) fn apply(&mut self, a: Act) {
        let s = &mut self.state;
        match a {
            Act::Select(e) => s.select(e),
            Act::Highlight(h) => {
                s.message = format!("{} highlighted", h.len());
                s.highlight(h);
            }
            Act::Thickness(id, t) => {
                s.set_thickness(id, t);
            }
            Act::Role(id, r) => {
                s.set_role(id, r);
            }
            Act::AddConstraint(a, b, k) => {
                s.add_constraint(a, b, k);
            }
            Act::RemoveConstraint(i) => {
                s.remove_constraint(i);
            }
            Act::Resize(id, lo, hi) => {
                s.resize_machining(id, lo, hi);
            }
            Act::SplitAt(id, z) => {
                s.split_machining_at(id, z);
            }
            Act::SplitLine(id, p, q) => {
                s.split_machining_by_line(id, p, q);
            }
            Act::Merge(a, b) => {
                s.merge_machining(a, b);
            }
            Act::Draw(owner, pts, lo, hi) => {
                if s.add_drawn_machining(owner, &pts, lo, hi) {
                    self.forms.draw_text.clear();
                }
            }
            Act::Spindle(id, rpm) => {
                s.set_spindle(id, rpm);
            }
            Act::Feed(id, r, f) => {
                s.set_feed(id, r, f);
            }
            Act::Connect(base, leaf, k) => {
                s.add_connection(base, leaf, k);
            }
            Act::Disconnect(a, b) => {
                s.remove_connection(a, b);
            }
        }
    }
}
