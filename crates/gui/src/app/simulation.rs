//! The sequence simulation: a slider over the machining order and, at
//! each step, the wall being cut and its deflection against the allowed.

use eframe::egui::{self, Color32};

use crate::relations;
use crate::state::Entity;

use super::ThinplanApp;

impl ThinplanApp {
    pub(super) fn simulation(&mut self, ui: &mut egui::Ui) {
        let Some(plan) = self.state.plan() else {
            return;
        };
        let n = plan.machining_features.len();
        ui.horizontal(|ui| {
            ui.add_enabled(
                n > 0,
                egui::Checkbox::new(&mut self.simulate, "Sequence simulation"),
            );
            if n == 0 {
                ui.label("(no machining features yet: run the stages)");
                return;
            }
            ui.add_enabled(
                self.simulate,
                egui::Slider::new(&mut self.sim_index, 0..=n - 1).text("step"),
            );
        });
        if let (true, Some(k), Some(knowledge)) =
            (self.simulate, self.state.sim_step, self.state.knowledge())
        {
            let order = relations::machining_order(plan);
            if let Some(id) = order.get(k) {
                let cur = relations::name(plan, Entity::Machining(*id));
                let mut line = format!(
                    "{}/{}: cutting {cur}; {k} removed, {} remaining",
                    k + 1,
                    n,
                    n - k - 1
                );
                let mut bad = false;
                if let Some(r) = relations::deflection_at(plan, knowledge, &order, k) {
                    bad = r.too_large();
                    line.push_str(&format!(
                        "; wall {} deflection {:.5} mm (allowed {:.4}, {:?}{})",
                        r.wall,
                        r.deflection,
                        r.allowed,
                        r.mode,
                        r.planned
                            .map_or(String::new(), |p| format!(", sized for {p:.5}"))
                    ));
                    if bad {
                        line.push_str(" — TOO LARGE");
                    }
                }
                ui.colored_label(
                    if bad {
                        Color32::from_rgb(255, 110, 90)
                    } else {
                        ui.visuals().text_color()
                    },
                    line,
                );
            }
        }
    }
}
