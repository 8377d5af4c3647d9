//! Stages 7 and 8: operations with modular tool paths, and their order.
//!
//! Per machining feature (after stage Resolve), the method of
//! `knowledge/methods.ron` that matches its adjacency picks the pattern, the
//! tool, stepovers, depths and entries (§6.3.3). Per z-level from the top
//! the modular pattern (§4.3.4, table 6.1) is built in the feature's frame:
//! rest-region passes (zigzag, one-way or a pocket spiral) over the
//! tool-centre region shrunk by the boundary stepover, then boundary passes
//! at exactly the tool radius from every product edge, down milling, with a
//! run-up; mirrored alternating z-levels where the method asks; ramp or helix
//! entries, never plunges; a separate product-adjacent bottom layer with
//! finishing conditions. Cutting conditions come from the material and tool;
//! times from `thinplan-feeds` under the machine's limits. [`order`] is
//! stage 8.

mod free;
pub mod geom;
mod layers;
pub mod links;
pub mod order;
pub mod path;
pub mod precedence;
mod rest;

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_feeds::MachineLimits;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{
    ArcMove, MachiningFeatureId, Operation, OperationId, PathMove, Plan, Provenance,
    ProvenanceSource, Refusal, Region3, Stage,
};

pub use order::{order, OrderError};

/// Provenance value (1) of an operation stage 8 runs at the end, with the
/// floor rest passes (`methods.<id>.wall_rest` with `run_last`).
pub const RUN_LAST: &str = "run_last";

/// Whether stage 8 runs `op` at the end, by tool, after every other
/// operation: floor rest passes, and wall rest passes the knowledge defers.
pub fn runs_last(op: &Operation) -> bool {
    op.provenance.rule.ends_with(".rest_pass") || op.provenance.values.get(RUN_LAST) == Some(&1.0)
}
pub use path::{Kind, LMove};

/// Why stage 7 could not run at all (a single feature that cannot be milled
/// is a refusal, not an error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OperationsError {
    #[error("stage {0:?} has not run: operations need resolved machining features")]
    MissingStage(Stage),
    #[error("the set-up names {what} `{id}`, which the knowledge does not have")]
    UnknownResource { what: &'static str, id: String },
}

/// The result of stage 7.
#[derive(Debug, Clone, PartialEq)]
pub struct Operations {
    pub operations: Vec<Operation>,
    /// Things a planner should look at (material left in sharp corners, a
    /// run-up that did not fit …), each naming the feature.
    pub warnings: Vec<String>,
    /// Features no operation was made for, with the reason.
    pub refusals: Vec<Refusal>,
}

impl Operations {
    /// Writes the operations into the plan: drops stale results from stage
    /// Operations on, then records this stage.
    pub fn apply_to(self, plan: &mut Plan) {
        plan.invalidate_from(Stage::Operations);
        plan.operations = self.operations;
        plan.refusals.extend(self.refusals);
        plan.stages_done.push(Stage::Operations);
    }
}

/// What `plan --json` shows per operation, read back from its provenance.
#[derive(Debug, Clone, PartialEq)]
pub struct OperationSummary {
    pub id: OperationId,
    pub feature: MachiningFeatureId,
    pub tool: String,
    pub pattern: String,
    pub layers: usize,
    pub length_mm: f64,
    pub time_s: f64,
}

/// The summary of an operation made by this stage.
pub fn summary(op: &Operation) -> OperationSummary {
    let v = |k: &str| op.provenance.values.get(k).copied().unwrap_or(0.0);
    let pattern = op
        .provenance
        .note
        .split(';')
        .find_map(|s| s.trim().strip_prefix("pattern="))
        .unwrap_or("")
        .to_string();
    OperationSummary {
        id: op.id,
        feature: op.feature,
        tool: op.tool.clone(),
        pattern,
        layers: v("layers") as usize,
        length_mm: v("length_mm"),
        time_s: v("time_s"),
    }
}

/// Stage 7: operations for every machining feature of the plan.
pub fn operations(plan: &Plan, k: &Knowledge) -> Result<Operations, OperationsError> {
    if !plan.stages_done.contains(&Stage::Resolve) {
        return Err(OperationsError::MissingStage(Stage::Resolve));
    }
    operations_unchecked(plan, k)
}

/// Stage 7 without the stage check (synthetic plans in tests and tools).
pub fn operations_unchecked(plan: &Plan, k: &Knowledge) -> Result<Operations, OperationsError> {
    let (machine, tools, limits) = resources(plan, k)?;
    let material =
        k.material(&plan.setup.material)
            .ok_or_else(|| OperationsError::UnknownResource {
                what: "material",
                id: plan.setup.material.clone(),
            })?;
    // Links that leave a feature's footprint clear every feature's top.
    let up = plan.setup.up.normalize_or_zero();
    let global_top = plan
        .machining_features
        .iter()
        .map(|f| f.shape.frame.origin.dot(up) + f.shape.z_max)
        .fold(f64::NEG_INFINITY, f64::max);
    let env = layers::Env {
        k,
        tools,
        material,
        machine,
        limits,
        global_top,
    };
    let mut out = Operations {
        operations: Vec::new(),
        warnings: Vec::new(),
        refusals: Vec::new(),
    };
    let (d_max, min_flute) = tools.reach_and_rise().unwrap_or((0.0, f64::INFINITY));
    let positions = precedence::machining_positions(plan);
    // How far a feature no tool fits alone may be reached from beside it:
    // the smallest tool's diameter times the largest overhang the method
    // knowledge allows beyond an open edge.
    let rest_reach = tools
        .tools
        .iter()
        .map(|t| t.diameter)
        .fold(f64::INFINITY, f64::min)
        * k.methods
            .methods
            .iter()
            .map(|m| m.overhang.open)
            .fold(0.0, f64::max);
    // The same edges stage 8 honours: what stands when a feature is cut.
    let shank_edges = precedence::shank_edges(plan, d_max, min_flute);
    // Features that get no operation, and every feature they cover from
    // the tool side (accessibility constraints): machining those would
    // plunge or rapid into material that is still there.
    // (reason, whether the material is unreachable in this set-up)
    let mut skipped: std::collections::BTreeMap<usize, (String, bool)> = plan
        .machining_features
        .iter()
        .enumerate()
        .filter(|(_, f)| f.provenance.values.get("access_blocked") == Some(&1.0))
        .map(|(i, _)| {
            (
                i,
                (
                    "unreachable in this set-up: the part covers it from the tool side \
                     (another set-up)"
                        .to_string(),
                    true,
                ),
            )
        })
        .collect();
    let mut made: Vec<Option<Result<layers::Made, String>>> =
        (0..plan.machining_features.len()).map(|_| None).collect();
    loop {
        for (i, f) in plan.machining_features.iter().enumerate() {
            if made[i].is_some() || skipped.contains_key(&i) {
                continue;
            }
            let free = free::free_space(plan, i, 2.0 * d_max);
            let removed = free::removed_space(plan, i, 2.0 * d_max, &positions);
            let obstacles = free::shank_obstacles(plan, i, d_max, min_flute, &shank_edges);
            // A geometry library panicking on an awkward profile
            // (cavalier_contours asserts on some degenerate offsets) refuses
            // this feature, not the plan.
            let attempt_on = |f: &thinplan_plan::MachiningFeature, env: &layers::Env| {
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    layers::feature_operations(f, env, free.as_ref(), removed.as_ref(), &obstacles)
                }))
                .unwrap_or_else(|_| {
                    Err("the offset geometry failed on this profile (library panic)".into())
                })
            };
            let attempt = |env: &layers::Env| attempt_on(f, env);
            let mut m = attempt(&env);
            // No tool fits its own region: reach it from the space cut
            // beside it (a pocket corner between the walls' steps).
            if matches!(&m, Err(e) if e.starts_with(layers::NO_TOOL_FITS)) {
                let grown = free
                    .as_ref()
                    .zip(removed.as_ref())
                    .and_then(|(free, removed)| {
                        rest::reached_from_beside(f, free, removed, rest_reach)
                    });
                if let Some(g) = grown {
                    if let Ok(mut made) = attempt_on(&g, &env) {
                        let note = format!(
                            "reached from the space cut beside it (region grown by up to \
                             {rest_reach:.3} mm: {:.1} → {:.1} mm²)",
                            layers::region_area(f),
                            layers::region_area(&g)
                        );
                        for op in &mut made.ops {
                            op.provenance.note.push_str(&format!("; {note}"));
                            op.provenance
                                .values
                                .insert("rest_reach_mm".into(), rest_reach);
                        }
                        made.warnings.insert(
                            0,
                            format!("{}: no tool fits its region alone; {note}", f.id),
                        );
                        m = Ok(made);
                    }
                }
            }
            // A path the safety net refused with one tool may pass with a
            // smaller one: retry without the largest tools, one at a time.
            let mut fewer = tools.clone();
            while matches!(&m, Err(e) if !e.starts_with(layers::NO_TOOL_FITS))
                && fewer.tools.len() > 1
            {
                let largest = fewer
                    .tools
                    .iter()
                    .enumerate()
                    .max_by(|a, b| {
                        a.1.diameter
                            .total_cmp(&b.1.diameter)
                            .then_with(|| b.1.id.cmp(&a.1.id))
                    })
                    .map(|(k, _)| k)
                    .expect("more than one tool");
                let dropped = fewer.tools.remove(largest);
                let first = m.as_ref().err().cloned().unwrap_or_default();
                let sub = env.clone_with_tools(&fewer);
                m = attempt(&sub);
                if let Ok(made) = &mut m {
                    made.warnings.insert(
                        0,
                        format!(
                            "{}: without {} ({first}); a smaller tool is used",
                            f.id, dropped.id
                        ),
                    );
                }
            }
            made[i] = Some(m);
        }
        let mut changed = false;
        for c in &plan.machining_constraints {
            if c.provenance.rule != "interference.accessibility" {
                continue;
            }
            let (a, b) = (c.first.0 as usize, c.second.0 as usize);
            let a_fails = skipped.contains_key(&a) || matches!(made[a], Some(Err(_)));
            if a_fails && !skipped.contains_key(&b) {
                // Below material no tool reaches, the same holds.
                let unreachable = match (&skipped.get(&a), &made[a]) {
                    (Some((_, u)), _) => *u,
                    (None, Some(Err(e))) => e.starts_with(layers::NO_TOOL_FITS),
                    _ => false,
                };
                let reason = if unreachable {
                    format!("unreachable: {} above it is", c.first)
                } else {
                    format!("{} above it gets no operation", c.first)
                };
                skipped.insert(b, (reason, unreachable));
                made[b] = None;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    for (i, f) in plan.machining_features.iter().enumerate() {
        if let Some((reason, unreachable)) = skipped.get(&i) {
            out.warnings
                .push(format!("{}: not machined: {reason}", f.id));
            let rule = if *unreachable {
                "operations.unreachable"
            } else {
                "operations.feature"
            };
            // Material covered from the tool side is an undercut: a height
            // field along the spindle (the stock simulation) never sees it.
            let seen = !f.provenance.values.contains_key("access_blocked")
                && !reason.contains("another set-up");
            let provenance = if *unreachable {
                unreachable_provenance(feature_volume(f), seen)
            } else {
                Provenance::new(ProvenanceSource::Default, rule)
            };
            out.refusals.push(Refusal {
                stage: Stage::Operations,
                rule: rule.into(),
                reason: format!("no operation for {}: {reason}", f.id),
                provenance,
            });
            continue;
        }
        let made = made[i].take().expect("computed above");
        match made {
            Ok(made) => {
                out.warnings.extend(made.warnings);
                for (reason, volume) in made.unreachable {
                    out.refusals.push(Refusal {
                        stage: Stage::Operations,
                        rule: "operations.unreachable".into(),
                        reason,
                        provenance: unreachable_provenance(volume, true),
                    });
                }
                for lo in made.ops {
                    let id = OperationId(out.operations.len() as u32);
                    out.operations.push(to_operation(id, f, lo, &env));
                }
            }
            Err(reason) => {
                out.warnings.push(format!("{}: {reason}", f.id));
                // No tool fits at all: unreachable material, not a failure.
                let unreachable = reason.starts_with(layers::NO_TOOL_FITS);
                let rule = if unreachable {
                    "operations.unreachable"
                } else {
                    "operations.feature"
                };
                let provenance = if unreachable {
                    unreachable_provenance(feature_volume(f), true)
                } else {
                    Provenance::new(ProvenanceSource::Default, rule)
                };
                out.refusals.push(Refusal {
                    stage: Stage::Operations,
                    rule: rule.into(),
                    reason: format!("no operation for {}: {reason}", f.id),
                    provenance,
                });
            }
        }
    }
    Ok(out)
}

/// A whole feature's volume (mm³): its region over its depth.
fn feature_volume(f: &thinplan_plan::MachiningFeature) -> f64 {
    layers::region_area(f) * (f.shape.z_max - f.shape.z_min).max(0.0)
}

/// Provenance of unreachable material: `volume_mm3`, the estimate, and
/// `seen_from_spindle` (1: open to the spindle, so a height-field stock
/// simulation counts it; 0: an undercut only another set-up reaches).
fn unreachable_provenance(volume: f64, seen: bool) -> Provenance {
    let mut p = Provenance::new(ProvenanceSource::Default, "operations.unreachable");
    p.values.insert("volume_mm3".into(), volume);
    p.values
        .insert("seen_from_spindle".into(), f64::from(u8::from(seen)));
    p
}

/// The set-up's machine and tool set from the knowledge, and the machine's
/// limits for the time model.
fn resources<'k>(
    plan: &Plan,
    k: &'k Knowledge,
) -> Result<
    (
        &'k thinplan_knowledge::Machine,
        &'k thinplan_knowledge::ToolSet,
        MachineLimits,
    ),
    OperationsError,
> {
    let unknown = |what: &'static str, id: &str| OperationsError::UnknownResource {
        what,
        id: id.to_string(),
    };
    let machine = k
        .machine(&plan.setup.machine)
        .ok_or_else(|| unknown("machine", &plan.setup.machine))?;
    let tools = k
        .tool_set(&plan.setup.tool_set)
        .ok_or_else(|| unknown("tool set", &plan.setup.tool_set))?;
    Ok((machine, tools, machine_limits(machine, k)))
}

/// The machine's limits for the time model.
fn machine_limits(machine: &thinplan_knowledge::Machine, k: &Knowledge) -> MachineLimits {
    MachineLimits {
        v_max: [machine.x.v_max, machine.y.v_max, machine.z.v_max],
        a_max: [machine.x.a_max, machine.y.a_max, machine.z.a_max],
        a_centripetal: machine.a_centripetal,
        corner_angle_deg: k.methods.corner_angle_deg,
    }
}

/// Length (mm) and time (s) of local moves from `start`, each with its
/// speed cap (mm/s), under `limits`: the one time model of every operation.
fn length_and_time<'a>(
    start: DVec3,
    moves: impl Iterator<Item = (&'a LMove, f64)>,
    limits: &MachineLimits,
) -> (f64, f64) {
    let mut from = start;
    let mut length = 0.0;
    let mut pts = vec![start];
    let mut caps = Vec::new();
    for (m, cap) in moves {
        length += path::move_length(from, m);
        for p in path::move_points(from, m, 1.0) {
            pts.push(p);
            caps.push(cap);
        }
        from = m.to;
    }
    let time = thinplan_feeds::schedule_polyline(&pts, &caps, limits).total_time;
    (length, time)
}

/// A local operation mapped to part coordinates with its feeds and time.
fn to_operation(
    id: OperationId,
    f: &thinplan_plan::MachiningFeature,
    lo: layers::LocalOp,
    env: &layers::Env,
) -> Operation {
    let fr = &f.shape.frame;
    let z = fr.z.normalize_or_zero();
    let x = (fr.x - z * fr.x.dot(z)).normalize_or_zero();
    let y = z.cross(x);
    let to_part = |p: DVec3| fr.origin + x * p.x + y * p.y + z * p.z;
    let to_part2 = |c: DVec2, zz: f64| fr.origin + x * c.x + y * c.y + z * zz;
    let feed = |kind: Kind| match kind {
        Kind::Rest | Kind::FullCut => lo.feed_rough,
        Kind::Boundary => lo.feed_boundary,
        Kind::BottomFinish => lo.feed_finish,
        Kind::Link => lo.feed_link,
        Kind::Rapid => 0.0,
    };
    let region = |kind: Kind| match kind {
        Kind::Rest | Kind::BottomFinish => Region3::Rest,
        Kind::FullCut => Region3::FullCut,
        Kind::Boundary => Region3::Boundary,
        Kind::Link => Region3::Link,
        Kind::Rapid => Region3::Rapid,
    };
    let mut moves = Vec::with_capacity(lo.moves.len());
    let rapid_cap = env.limits.v_max.iter().copied().fold(0.0, f64::max);
    let cap = |m: &LMove| {
        if m.kind == Kind::Rapid {
            rapid_cap
        } else {
            feed(m.kind) / 60.0
        }
    };
    let (length, time) =
        length_and_time(lo.start, lo.moves.iter().map(|m| (m, cap(m))), &env.limits);
    for m in &lo.moves {
        moves.push(PathMove {
            to: to_part(m.to),
            arc: m.arc.map(|(c, ccw)| ArcMove {
                centre: to_part2(c, m.to.z),
                axis: z,
                clockwise: !ccw,
            }),
            feed: feed(m.kind),
            region: region(m.kind),
        });
    }
    let mut prov = lo.provenance;
    prov.values.insert("length_mm".into(), length);
    prov.values.insert("time_s".into(), time);
    Operation {
        id,
        feature: f.id,
        method: lo.method,
        tool: lo.tool,
        tool_axis: z,
        spindle_rpm: lo.rpm,
        start: to_part(lo.start),
        moves,
        provenance: prov,
        link_z: None,
    }
}

/// Per-operation numbers by id (for reports and benchmarks).
pub fn summaries(plan: &Plan) -> BTreeMap<OperationId, OperationSummary> {
    plan.operations.iter().map(|o| (o.id, summary(o))).collect()
}
