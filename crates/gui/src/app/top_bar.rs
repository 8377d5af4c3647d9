//! The top bar: the part and plan files, running the stages (and
//! cancelling a run), undo and redo, and the stages done.

use std::path::PathBuf;

use eframe::egui::{self, Color32, RichText};
use thinplan_plan::Stage;

use super::files::Picking;
use super::ThinplanApp;

impl ThinplanApp {
    pub(super) fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            ui.label("Part:");
            ui.add(egui::TextEdit::singleline(&mut self.forms.part_source).desired_width(220.0));
            egui::ComboBox::from_id_salt("samples")
                .selected_text("samples")
                .show_ui(ui, |ui| {
                    for (name, _) in thinplan_import::SAMPLES {
                        if ui.selectable_label(false, *name).clicked() {
                            self.forms.part_source = format!("builtin:{name}");
                        }
                    }
                });
            if ui.button("Open part").clicked() {
                let src = self.forms.part_source.trim().to_string();
                self.open_part(&src);
            }
            if ui.button("Browse…").clicked() {
                self.pick(Picking::Part);
            }
            ui.separator();
            let running = self.state.is_running();
            ui.add_enabled_ui(!running, |ui| {
                let next = self.state.session().and_then(|s| s.next_stage());
                let label = match next {
                    Some(s) => format!("Run next stage ({s:?})"),
                    None => "Run next stage".into(),
                };
                if ui.button(label).clicked() {
                    self.state.run_next();
                }
                if ui.button("Run all").clicked() {
                    self.state.run_all();
                }
            });
            if let Some((label, stage)) = self.state.job_progress() {
                ui.spinner();
                ui.label(match stage {
                    Some(s) => format!("{label}: {s:?}…"),
                    None => format!("{label}…"),
                });
                if ui.button("Cancel").clicked() {
                    self.state.cancel();
                }
            }
            ui.separator();
            ui.add_enabled_ui(!running, |ui| {
                let u = self.state.history.undo_label().map(str::to_string);
                let r = self.state.history.redo_label().map(str::to_string);
                if ui
                    .add_enabled(u.is_some(), egui::Button::new("Undo"))
                    .on_hover_text(u.unwrap_or_default())
                    .clicked()
                {
                    self.state.undo();
                }
                if ui
                    .add_enabled(r.is_some(), egui::Button::new("Redo"))
                    .on_hover_text(r.unwrap_or_default())
                    .clicked()
                {
                    self.state.redo();
                }
            });
            ui.separator();
            ui.label("Plan file:");
            ui.add(egui::TextEdit::singleline(&mut self.forms.plan_path).desired_width(160.0));
            if ui.button("Save plan").clicked() {
                let p = PathBuf::from(self.forms.plan_path.trim());
                self.state.save_plan(&p);
            }
            if ui.button("Open plan").clicked() {
                let p = PathBuf::from(self.forms.plan_path.trim());
                if self.state.open_plan(&p) {
                    self.fill_forms_from_plan();
                }
            }
            if ui.button("Browse plans…").clicked() {
                self.pick(Picking::Plan);
            }
        });
        if let Some(p) = self.state.plan() {
            ui.horizontal(|ui| {
                ui.label("Stages done:");
                for s in Stage::ALL {
                    let done = p.stages_done.contains(&s);
                    let text = RichText::new(format!("{s:?}"));
                    ui.label(if done {
                        text.color(Color32::from_rgb(110, 200, 110))
                    } else {
                        text.weak()
                    });
                }
            });
        }
    }
}
