//! The inspector's section for drawing a free-shaped machining feature:
//! a plan view of the owner's features where clicks add points, the
//! points as text (typed or clicked), the z range along up.

use eframe::egui::{self, Color32, Pos2, Sense, Stroke};
use glam::{DVec2, DVec3};
use thinplan_plan::{Plan, StiffnessFeatureId};

use crate::edit;

use super::actions::Act;
use super::Forms;

fn setup_frame(plan: &Plan) -> thinplan_brep::Frame {
    thinplan_brep::Frame::from_axis_ref(DVec3::ZERO, plan.setup.up, None)
}

/// The owner's machining features as outlines in the set-up's plan
/// view (arcs as chords).
fn outlines(plan: &Plan, owner: StiffnessFeatureId) -> Vec<Vec<DVec2>> {
    let f = setup_frame(plan);
    plan.machining_features
        .iter()
        .filter(|m| m.owner == owner)
        .map(|m| {
            let fr = &m.shape.frame;
            let x = fr.x.normalize_or_zero();
            let y = fr.z.normalize_or_zero().cross(x);
            crate::scene::loop_points(&m.shape.region.outer)
                .into_iter()
                .map(|p| {
                    let w = fr.origin + x * p.x + y * p.y;
                    DVec2::new(w.dot(f.x), w.dot(f.y))
                })
                .collect()
        })
        .collect()
}

/// The z range (along up) the owner's features span; else the part's.
pub(super) fn plan_z_range(plan: &Plan, owner: StiffnessFeatureId) -> (f64, f64) {
    let f = setup_frame(plan);
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for m in plan.machining_features.iter().filter(|m| m.owner == owner) {
        let o = m.shape.frame.origin.dot(f.z);
        let s = m.shape.frame.z.normalize_or_zero().dot(f.z);
        for z in [o + s * m.shape.z_min, o + s * m.shape.z_max] {
            lo = lo.min(z);
            hi = hi.max(z);
        }
    }
    if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

pub(super) fn draw_section(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    owner: StiffnessFeatureId,
    acts: &mut Vec<Act>,
) {
    egui::CollapsingHeader::new(format!("Draw a machining feature of {owner}"))
        .id_salt("draw")
        .show(ui, |ui| {
            let shapes = outlines(plan, owner);
            let points = edit::parse_points(&forms.draw_text);
            let typed: &[DVec2] = points.as_deref().unwrap_or(&[]);
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for p in shapes.iter().flatten().chain(typed) {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
            if !lo.is_finite() {
                let b = plan.part.summary.bbox;
                (lo, hi) = (DVec2::ZERO, DVec2::new(b[0].max(1.0), b[1].max(1.0)));
            }
            let pad = (hi - lo).max_element() * 0.1 + 1.0;
            (lo, hi) = (lo - DVec2::splat(pad), hi + DVec2::splat(pad));
            let (rect, resp) = ui.allocate_exact_size(
                egui::vec2(ui.available_width().min(300.0), 180.0),
                Sense::click(),
            );
            // Named for screen readers and the headless tests.
            resp.widget_info(|| {
                egui::WidgetInfo::labeled(egui::WidgetType::Other, true, "plan view to draw in")
            });
            let scale =
                ((rect.width() as f64) / (hi.x - lo.x)).min((rect.height() as f64) / (hi.y - lo.y));
            let to_screen = |p: DVec2| {
                Pos2::new(
                    rect.min.x + ((p.x - lo.x) * scale) as f32,
                    rect.max.y - ((p.y - lo.y) * scale) as f32,
                )
            };
            let painter = ui.painter_at(rect);
            painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
            for s in &shapes {
                let pts: Vec<Pos2> = s.iter().map(|p| to_screen(*p)).collect();
                painter.add(egui::Shape::closed_line(
                    pts,
                    Stroke::new(1.0, Color32::from_rgb(120, 140, 170)),
                ));
            }
            let pts: Vec<Pos2> = typed.iter().map(|p| to_screen(*p)).collect();
            if pts.len() > 1 {
                painter.add(egui::Shape::closed_line(
                    pts.clone(),
                    Stroke::new(1.5, Color32::from_rgb(255, 200, 40)),
                ));
            }
            for p in &pts {
                painter.circle_filled(*p, 2.5, Color32::from_rgb(255, 200, 40));
            }
            if let Some(c) = resp.interact_pointer_pos().filter(|_| resp.clicked()) {
                // Clicks snap to 0.1 mm in the set-up frame.
                let x = ((c.x - rect.min.x) as f64 / scale + lo.x) * 10.0;
                let y = ((rect.max.y - c.y) as f64 / scale + lo.y) * 10.0;
                let sep = if forms.draw_text.trim().is_empty() {
                    ""
                } else {
                    "; "
                };
                forms.draw_text = format!(
                    "{}{sep}{:.1}, {:.1}",
                    forms.draw_text.trim().trim_end_matches(';'),
                    x.round() / 10.0,
                    y.round() / 10.0
                );
            }
            ui.label("points (x, y; … in the set-up's plan view, mm): click above or type");
            ui.add(egui::TextEdit::singleline(&mut forms.draw_text).id_salt("draw points"));
            ui.horizontal(|ui| {
                ui.label("z from");
                ui.add(egui::DragValue::new(&mut forms.draw_z.0).speed(0.05));
                ui.label("to");
                ui.add(egui::DragValue::new(&mut forms.draw_z.1).speed(0.05));
            });
            ui.horizontal(|ui| {
                if ui.button("Clear points").clicked() {
                    forms.draw_text.clear();
                }
                match &points {
                    Ok(p) => {
                        if ui.button("Add drawn feature").clicked() {
                            acts.push(Act::Draw(owner, p.clone(), forms.draw_z.0, forms.draw_z.1));
                        }
                    }
                    Err(e) => {
                        ui.colored_label(Color32::LIGHT_RED, e);
                    }
                }
            });
        });
}
