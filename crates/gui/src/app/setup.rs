//! The set-up (up direction, machine, tools, material) and knowledge
//! sections of the right panel.

use std::path::PathBuf;

use eframe::egui::{self, Color32};
use thinplan_pipeline::SetupRequest;

use super::ThinplanApp;

impl ThinplanApp {
    pub(super) fn setup_request(&self) -> SetupRequest {
        SetupRequest {
            setup_file: None,
            up: crate::state::parse_up(&self.forms.up).ok(),
            machine: Some(self.forms.machine.clone()).filter(|s| !s.is_empty()),
            tool_set: Some(self.forms.tool_set.clone()).filter(|s| !s.is_empty()),
            material: Some(self.forms.material.clone()).filter(|s| !s.is_empty()),
        }
    }

    pub(super) fn setup_and_knowledge(&mut self, ui: &mut egui::Ui) {
        egui::CollapsingHeader::new("Set-up")
            .default_open(false)
            .show(ui, |ui| {
                let Some(k) = self.state.knowledge() else {
                    ui.label("no part open");
                    return;
                };
                let (machines, tools, materials): (Vec<String>, Vec<String>, Vec<String>) = (
                    k.machines.keys().cloned().collect(),
                    k.tool_sets.keys().cloned().collect(),
                    k.materials.keys().cloned().collect(),
                );
                egui::Grid::new("setup").num_columns(2).show(ui, |ui| {
                    ui.label("up (x, y, z)");
                    ui.text_edit_singleline(&mut self.forms.up);
                    ui.end_row();
                    for (label, list, value) in [
                        ("machine", &machines, &mut self.forms.machine),
                        ("tools", &tools, &mut self.forms.tool_set),
                        ("material", &materials, &mut self.forms.material),
                    ] {
                        ui.label(label);
                        egui::ComboBox::from_id_salt(label)
                            .selected_text(value.as_str())
                            .show_ui(ui, |ui| {
                                for m in list {
                                    ui.selectable_value(value, m.clone(), m);
                                }
                            });
                        ui.end_row();
                    }
                });
                if let Err(e) = crate::state::parse_up(&self.forms.up) {
                    ui.colored_label(Color32::LIGHT_RED, e);
                } else if ui.button("Apply set-up").clicked() {
                    let req = self.setup_request();
                    self.state.apply_setup(&req);
                }
            });
        egui::CollapsingHeader::new("Export").show(ui, |ui| self.export_form(ui));
        // Kept open while the knowledge has errors: they must be seen.
        let errors = !self.state.knowledge_status.errors.is_empty();
        egui::CollapsingHeader::new("Knowledge")
            .open(errors.then_some(true))
            .show(ui, |ui| {
                let origin = self
                    .state
                    .knowledge()
                    .map(|k| k.origin.clone())
                    .unwrap_or_default();
                ui.label(format!("in use: {origin}"));
                ui.horizontal(|ui| {
                    ui.label("directory:");
                    ui.text_edit_singleline(&mut self.forms.knowledge_dir);
                });
                ui.horizontal(|ui| {
                    if ui.button("Load / reload").clicked() {
                        let d = PathBuf::from(self.forms.knowledge_dir.trim());
                        self.state.load_knowledge(Some(&d));
                    }
                    if ui.button("Built-in").clicked() {
                        self.state.load_knowledge(None);
                    }
                });
                for e in &self.state.knowledge_status.errors {
                    ui.colored_label(Color32::LIGHT_RED, e);
                }
            });
    }
}
