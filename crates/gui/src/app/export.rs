//! The export section: post-processor, G-code and set-up sheet files, and
//! the verification's verdict that allows or refuses the export.

use std::path::PathBuf;

use eframe::egui;

use super::ThinplanApp;

impl ThinplanApp {
    pub(super) fn export_form(&mut self, ui: &mut egui::Ui) {
        let Some(k) = self.state.knowledge() else {
            ui.label("no part open");
            return;
        };
        let posts: Vec<String> = k.posts.keys().cloned().collect();
        if self.forms.post.is_empty() {
            self.forms.post = thinplan_knowledge::DEFAULT_POST.to_string();
        }
        if self.forms.gcode_path.is_empty() {
            let stem = self
                .state
                .plan()
                .map(|p| export_stem(&p.part.source))
                .unwrap_or_else(|| "part".into());
            self.forms.gcode_path = format!("{stem}.ngc");
            self.forms.sheet_path = format!("{stem}.sheet.html");
        }
        egui::Grid::new("export").num_columns(2).show(ui, |ui| {
            ui.label("post");
            egui::ComboBox::from_id_salt("post")
                .selected_text(self.forms.post.as_str())
                .show_ui(ui, |ui| {
                    for p in &posts {
                        ui.selectable_value(&mut self.forms.post, p.clone(), p);
                    }
                });
            ui.end_row();
            ui.label("G-code file");
            ui.add(egui::TextEdit::singleline(&mut self.forms.gcode_path).id_salt("gcode path"));
            ui.end_row();
            ui.label("setup sheet");
            ui.add(egui::TextEdit::singleline(&mut self.forms.sheet_path).id_salt("sheet path"));
            ui.end_row();
        });
        let verification = self.state.plan().and_then(|p| p.verification.as_ref());
        let verdict = verification.map(|v| v.verdict);
        match verification {
            None => {
                ui.label("verdict: not verified (run all stages)");
            }
            Some(v) => {
                let colour = match v.verdict {
                    thinplan_plan::Verdict::Safe => egui::Color32::from_rgb(40, 140, 60),
                    thinplan_plan::Verdict::Incomplete => egui::Color32::from_rgb(190, 130, 20),
                    thinplan_plan::Verdict::Unsafe => egui::Color32::from_rgb(200, 40, 40),
                };
                ui.colored_label(colour, format!("verdict: {}", v.verdict.name()));
                for l in &v.left {
                    ui.label(format!(
                        "left {:.1} mm³ ({})",
                        l.volume_mm3,
                        l.reason.name()
                    ));
                }
                if !v.removed.is_empty() {
                    ui.label(format!(
                        "{} operation(s) removed by the verification",
                        v.removed.len()
                    ));
                }
                for p in v.problems.iter().take(5) {
                    ui.label(format!(
                        "{} by {}",
                        p.kind.name(),
                        p.operation
                            .map_or_else(|| "-".to_string(), |o| o.to_string())
                    ));
                }
            }
        }
        let ready = verdict.is_some_and(|v| v != thinplan_plan::Verdict::Unsafe);
        if ui
            .add_enabled(ready, egui::Button::new("Export G-code and sheet"))
            .on_disabled_hover_text(if verdict.is_some() {
                "the verification found the program unsafe: no program is written"
            } else {
                "run all stages first"
            })
            .clicked()
        {
            let g = PathBuf::from(self.forms.gcode_path.trim());
            let sheet = self.forms.sheet_path.trim();
            let sheet = (!sheet.is_empty()).then(|| PathBuf::from(sheet));
            let post = self.forms.post.clone();
            self.state.export(&g, sheet.as_deref(), &post);
        }
    }
}

/// A file name stem for exports from a part source (`builtin:wing_rib`,
/// `dir/part.step` → `wing_rib`, `part`).
fn export_stem(source: &str) -> String {
    let name = source.trim_start_matches("builtin:");
    let file = std::path::Path::new(name)
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| "part".into());
    file.split('.')
        .next()
        .filter(|s| !s.is_empty())
        .unwrap_or("part")
        .to_string()
}
