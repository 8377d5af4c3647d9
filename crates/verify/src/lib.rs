//! Stage 9, verification (DESIGN.md "The pipeline", §5.4.3): the program
//! the plan would write is posted, replayed on a Z-map of the blank by the
//! independent stock simulation (`thinplan-stocksim`, which reads only the
//! G-code text), and checked for gouges, rapids through stock, feed plunges
//! into solid stock, cuts above the flutes, and holder collisions with the
//! in-process stock (`thinplan-collision`). An operation that makes a problem
//! is taken out of the order and refused with the reason, and the program
//! is replayed again, a bounded number of rounds. The result is a
//! [`Verification`] with a verdict: `safe`, `incomplete` (what is left and
//! why) or `unsafe` (each problem and its operation); drivers write no
//! program for an unsafe verdict.

use std::collections::BTreeMap;

use thinplan_brep::Brep;
use thinplan_knowledge::{Knowledge, VerificationKnowledge};
use thinplan_plan::{
    LeftMaterial, LeftReason, OperationId, Plan, Problem, ProblemKind, Provenance,
    ProvenanceSource, Refusal, RemovedOperation, Replan, ReplannedOperation, Stage, Verdict,
    Verification,
};
use thinplan_stocksim::{
    parse, parse_tool_table, simulate, CellClass, Crash, CrashKind, DefectSummary, MoveChecks,
    SimConfig,
};

/// Why the verification could not run at all.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyError(pub String);

impl std::fmt::Display for VerifyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for VerifyError {}

/// One replay of the program as the plan stands.
struct Replay {
    problems: Vec<Problem>,
    left: Vec<LeftMaterial>,
}

/// Runs stage 9 on `plan` (which must have its operation order): replays,
/// removes failing operations, replays again, and stores the
/// [`Verification`] in the plan.
pub fn verify(plan: &mut Plan, brep: &Brep, k: &Knowledge) -> Result<(), VerifyError> {
    plan.invalidate_from(Stage::Verify);
    let cfg = &k.verification;
    let planned_order = plan.operation_order.clone();
    let up = plan.setup.up;
    if (up - glam::DVec3::Z).length() > 1e-9 {
        return Err(VerifyError(format!(
            "the set-up's up ({:.3}, {:.3}, {:.3}) is not +Z: the program cannot be replayed \
             on a Z-map in part coordinates; no program is verified for this set-up",
            up.x, up.y, up.z
        )));
    }
    let mut removed: Vec<RemovedOperation> = Vec::new();
    let mut replanned: Vec<ReplannedOperation> = Vec::new();
    let mut links: BTreeMap<OperationId, f64> = BTreeMap::new();
    let mut rounds = 0;
    let replay = loop {
        rounds += 1;
        let r = replay(plan, brep, k, cfg)?;
        if r.problems.is_empty() || rounds >= cfg.max_rounds + cfg.max_removal_rounds {
            break r;
        }
        let culprits = culprits(&r.problems);
        if culprits.is_empty() {
            break r; // problems no operation made: nothing to take out
        }
        // In program order: operations sent to the end keep theirs.
        let mut culprits: Vec<(OperationId, Problem)> = culprits.into_iter().collect();
        let at = |op: &OperationId| plan.operation_order.iter().position(|o| o == op);
        culprits.sort_by_key(|(op, _)| at(op));
        for (op, problem) in culprits {
            let kind = problem.kind;
            // A plunge stage 8 took for air: planned again once, every
            // descent a ramp from where it starts; removed if it fails again.
            // Planning again needs a replay to judge it and, should it fail,
            // one more to confirm its removal: not in the last two rounds.
            let tried = |how| {
                rounds + 2 > cfg.max_rounds
                    || replanned
                        .iter()
                        .any(|r: &ReplannedOperation| r.operation == op && r.how == how)
            };
            if kind == ProblemKind::PlungeIntoStock && !tried(Replan::RampedEntries) {
                let before = plan.operations.iter().find(|o| o.id == op).cloned();
                let ramped =
                    thinplan_operations::links::ramp_every_descent(plan, k, op, problem.depth_mm)
                        .map_err(|e| VerifyError(format!("re-planning {op}'s entries: {e}")))?;
                if let (true, Some(planned)) = (ramped > 0, before) {
                    replanned.push(ReplannedOperation {
                        operation: op,
                        problem,
                        how: Replan::RampedEntries,
                        round: rounds,
                        planned,
                    });
                    continue;
                }
            }
            // A rapid that met stock: once, the operation's links go over
            // the top, the link into it too.
            if kind == ProblemKind::RapidThroughStock && !tried(Replan::LinksOverTop) {
                let before = plan.operations.iter().find(|o| o.id == op).cloned();
                let top = brep.bbox().max.z + k.methods.safe_clearance;
                let raised = thinplan_operations::links::raise_links(plan, k, op, top)
                    .map_err(|e| VerifyError(format!("re-planning {op}'s links: {e}")))?;
                let into = plan
                    .operations
                    .iter()
                    .find(|o| o.id == op)
                    .is_some_and(|o| o.link_z.is_some());
                clear_link(plan, op, &mut links);
                if let (true, Some(planned)) = (raised > 0 || into, before) {
                    replanned.push(ReplannedOperation {
                        operation: op,
                        problem,
                        how: Replan::LinksOverTop,
                        round: rounds,
                        planned,
                    });
                    continue;
                }
            }
            // Material that still stood (or a plunge no ramp fits): once,
            // the operation runs last, when everything else has cut.
            if matches!(
                kind,
                ProblemKind::ShankContact
                    | ProblemKind::HolderCollision
                    | ProblemKind::PlungeIntoStock
            ) && !tried(Replan::RunLast)
            {
                let before = plan.operations.iter().find(|o| o.id == op).cloned();
                if let (Some(planned), true) = (before, run_last(plan, op, &mut links)) {
                    replanned.push(ReplannedOperation {
                        operation: op,
                        problem,
                        how: Replan::RunLast,
                        round: rounds,
                        planned,
                    });
                    continue;
                }
            }
            let Some(operation) = remove_operation(plan, op, &mut links) else {
                continue;
            };
            removed.push(RemovedOperation {
                operation: op,
                problem,
                round: rounds,
                removed: operation,
            });
            plan.refusals.push(Refusal {
                stage: Stage::Verify,
                rule: "verification.remove_failing_operation".into(),
                reason: format!(
                    "{op} removed from the program: its moves make a {} (replay {rounds})",
                    kind.name()
                ),
                provenance: Provenance::new(ProvenanceSource::Knowledge, "verification"),
            });
        }
        if plan.operation_order.is_empty() {
            break Replay {
                problems: Vec::new(),
                left: Vec::new(),
            };
        }
    };
    let verdict = verdict_of(plan, &replay, &removed, cfg);
    plan.verification = Some(Verification {
        verdict,
        problems: replay.problems,
        left: replay.left,
        removed,
        replanned,
        planned_links: links,
        planned_order,
        rounds,
        cell_mm: cfg.cell,
        tolerance_mm: cfg.tolerance,
        provenance: Provenance::new(ProvenanceSource::Knowledge, "verification")
            .with_value("cell", cfg.cell)
            .with_value("tolerance", cfg.tolerance)
            .with_value("wall_tolerance", cfg.wall_tolerance)
            .with_value("grids", cfg.grid_shifts.len() as f64)
            .with_value("max_missed_mm3", cfg.max_missed_mm3)
            .with_value("max_unreachable_mm3", cfg.max_unreachable_mm3)
            .with_value("max_descent_deg", cfg.max_descent_deg)
            .with_value("max_plunge_mm3", cfg.max_plunge_mm3)
            .with_value("max_rounds", cfg.max_rounds as f64)
            .with_value("max_removal_rounds", cfg.max_removal_rounds as f64),
    });
    plan.stages_done.push(Stage::Verify);
    Ok(())
}

fn verdict_of(
    plan: &Plan,
    r: &Replay,
    removed: &[RemovedOperation],
    cfg: &VerificationKnowledge,
) -> Verdict {
    if !r.problems.is_empty() {
        return Verdict::Unsafe;
    }
    let sum = |reason| {
        r.left
            .iter()
            .filter(|l| l.reason == reason)
            .map(|l| l.volume_mm3)
            .sum::<f64>()
    };
    let nothing_cut = plan.operation_order.is_empty() && !plan.machining_features.is_empty();
    let left_over = sum(LeftReason::Missed) + sum(LeftReason::AboveReach) > cfg.max_missed_mm3
        || sum(LeftReason::Unreachable) > cfg.max_unreachable_mm3;
    let refused_features = plan
        .refusals
        .iter()
        .any(|r| matches!(r.stage, Stage::Operations | Stage::Order));
    if nothing_cut || left_over || !removed.is_empty() || refused_features {
        Verdict::Incomplete
    } else {
        Verdict::Safe
    }
}

/// The operations to take out: each problem's operation, with its first
/// problem.
fn culprits(problems: &[Problem]) -> BTreeMap<OperationId, Problem> {
    let mut out = BTreeMap::new();
    for p in problems {
        if let Some(op) = p.operation {
            out.entry(op).or_insert_with(|| p.clone());
        }
    }
    out
}

/// Sends the link into operation `id` over the top (the operation before
/// it changed), keeping the lowered height stage 8 planned in `links`.
fn clear_link(plan: &mut Plan, id: OperationId, links: &mut BTreeMap<OperationId, f64>) {
    if let Some(o) = plan.operations.iter_mut().find(|o| o.id == id) {
        if let Some(z) = o.link_z.take() {
            links.entry(id).or_insert(z);
        }
    }
}

/// Takes `op` out of the order; the operation after it no longer follows
/// the one its link was planned from, so its link goes over the top.
/// Returns where it stood.
fn take_from_order(
    plan: &mut Plan,
    op: OperationId,
    links: &mut BTreeMap<OperationId, f64>,
) -> Option<usize> {
    let pos = plan.operation_order.iter().position(|o| *o == op)?;
    plan.operation_order.remove(pos);
    if let Some(next) = plan.operation_order.get(pos).copied() {
        clear_link(plan, next, links);
    }
    Some(pos)
}

/// Takes `op` out of the program (order and operations).
fn remove_operation(
    plan: &mut Plan,
    op: OperationId,
    links: &mut BTreeMap<OperationId, f64>,
) -> Option<thinplan_plan::Operation> {
    take_from_order(plan, op, links)?;
    let at = plan.operations.iter().position(|o| o.id == op)?;
    Some(plan.operations.remove(at))
}

/// Moves `op` to the end of the order, its link over the top; false when
/// it is last already (or not in the order).
fn run_last(plan: &mut Plan, op: OperationId, links: &mut BTreeMap<OperationId, f64>) -> bool {
    if plan.operation_order.last() == Some(&op) {
        return false;
    }
    if take_from_order(plan, op, links).is_none() {
        return false;
    }
    plan.operation_order.push(op);
    if let Some(o) = plan.operations.iter_mut().find(|o| o.id == op) {
        o.link_z = None;
    }
    true
}

fn replay(
    plan: &Plan,
    brep: &Brep,
    k: &Knowledge,
    cfg: &VerificationKnowledge,
) -> Result<Replay, VerifyError> {
    if plan.operation_order.is_empty() {
        return Ok(Replay {
            problems: Vec::new(),
            left: Vec::new(),
        });
    }
    let post = k.post(&cfg.post).ok_or_else(|| {
        VerifyError(format!(
            "verification: the knowledge has no post `{}`",
            cfg.post
        ))
    })?;
    let tools = k.tool_set(&plan.setup.tool_set).ok_or_else(|| {
        VerifyError(format!(
            "verification: the knowledge has no tool set `{}`",
            plan.setup.tool_set
        ))
    })?;
    let nc = thinplan_post::post(plan, post, tools)
        .map_err(|e| VerifyError(format!("verification: cannot post the plan: {e}")))?;
    let program = parse(&nc.text, "verification.ngc").map_err(|e| {
        VerifyError(format!(
            "verification: the posted program does not read: {e}"
        ))
    })?;
    let table = parse_tool_table(&nc.tool_table, "verification.tbl")
        .map_err(|e| VerifyError(format!("verification: the tool table does not read: {e}")))?;
    // Tool numbers are positions in the set (the post's tool table).
    let flute_length = tools
        .tools
        .iter()
        .enumerate()
        .map(|(i, t)| (i as u32 + 1, t.flute_length))
        .collect();
    let sim_cfg = SimConfig {
        cell: cfg.cell,
        tol: cfg.tolerance,
        wall_tol: cfg.wall_tolerance,
        grid_shift: 0.0,
        blank: None,
        checks: MoveChecks {
            flute_length,
            max_descent_deg: Some(cfg.max_descent_deg),
            max_plunge_mm3: cfg.max_plunge_mm3,
            tol: cfg.tolerance,
            rim: cfg.wall_tolerance,
            operations: nc
                .operation_lines
                .iter()
                .map(|(l, id)| (*l, id.0))
                .collect(),
        },
    };
    // The grids are independent replays: each on its own thread, the
    // results taken in the knowledge's order. Only the first undoes an
    // operation as it fails and judges the rest without it; the others
    // replay the program as written, so that a graze one of them alone
    // sees (a plunge just over its limit) adds that problem, not every
    // one its undoing would then cause further on.
    let sims: Vec<Result<thinplan_stocksim::Simulation, String>> = std::thread::scope(|scope| {
        let runs: Vec<_> = cfg
            .grid_shifts
            .iter()
            .enumerate()
            .map(|(g, &shift)| {
                let mut cfg = SimConfig {
                    grid_shift: shift,
                    ..sim_cfg.clone()
                };
                if g > 0 {
                    cfg.checks.operations.clear();
                }
                let (program, table) = (&program, &table);
                scope.spawn(move || simulate(brep, program, table, &cfg).map_err(|e| e.to_string()))
            })
            .collect();
        runs.into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err("the replay stopped unexpectedly".into()))
            })
            .collect()
    });
    let mut problems: Vec<Problem> = Vec::new();
    let mut left: Vec<LeftMaterial> = Vec::new();
    for (g, sim) in sims.into_iter().enumerate() {
        let sim = sim.map_err(|e| VerifyError(format!("verification: the replay failed: {e}")))?;
        // A later grid adds what the earlier ones did not see.
        for p in grid_problems(&sim, &nc) {
            if !problems
                .iter()
                .any(|q| q.kind == p.kind && q.operation == p.operation)
            {
                problems.push(p);
            }
        }
        if g == 0 {
            let r = &sim.report;
            left = [
                (LeftReason::Missed, &r.leftover_missed),
                (LeftReason::AboveReach, &r.leftover_above_reach),
                (LeftReason::Unreachable, &r.leftover_unreachable),
            ]
            .into_iter()
            .filter(|(_, d)| d.cells > 0)
            .map(|(reason, d)| left_of(reason, d))
            .collect();
        }
    }
    problems.extend(holder_collisions(plan, k, brep));
    Ok(Replay { problems, left })
}

/// What one replay found: operations undone as they cut, each judged on
/// the stock the ones before it leave; crashes; gouges.
fn grid_problems(
    sim: &thinplan_stocksim::Simulation,
    nc: &thinplan_post::NcProgram,
) -> Vec<Problem> {
    let problem = |c: &Crash, operation: Option<OperationId>| Problem {
        kind: match c.kind {
            CrashKind::RapidIntoStock => ProblemKind::RapidThroughStock,
            CrashKind::SpindleOff => ProblemKind::SpindleOff,
            CrashKind::PlungeIntoStock => ProblemKind::PlungeIntoStock,
            CrashKind::ShankContact => ProblemKind::ShankContact,
            CrashKind::Gouge => ProblemKind::Gouge,
        },
        operation,
        line: Some(c.line),
        at: c.at,
        depth_mm: c.depth_mm,
        volume_mm3: c.volume_mm3,
    };
    let mut problems: Vec<Problem> = sim
        .report
        .excluded
        .iter()
        .map(|(id, c)| problem(c, Some(OperationId(*id))))
        .collect();
    for c in &sim.report.crashes {
        problems.push(problem(c, nc.operation_at(c.line)));
    }
    problems.extend(gouges(sim, nc));
    problems
}

fn left_of(reason: LeftReason, d: &DefectSummary) -> LeftMaterial {
    LeftMaterial {
        reason,
        volume_mm3: d.volume_mm3,
        worst_mm: d.worst_mm,
        at: d.worst_at,
        patches: d.regions_total,
    }
}

/// One problem per operation that last cut a gouged cell: the deepest of
/// its cells, and the volume of all of them.
fn gouges(sim: &thinplan_stocksim::Simulation, nc: &thinplan_post::NcProgram) -> Vec<Problem> {
    let grid = &sim.stock.grid;
    let area = grid.cell_area();
    let mut by_op: BTreeMap<Option<OperationId>, Problem> = BTreeMap::new();
    for (idx, class) in sim.classes.iter().enumerate() {
        if *class != CellClass::Gouge {
            continue;
        }
        let line = sim.stock.last_line[idx] as usize;
        let op = (line > 0).then(|| nc.operation_at(line)).flatten();
        let stock = sim.stock.top[idx] as f64;
        let depth = (sim.part[idx] as f64 - stock).max(0.0);
        let c = grid.center(idx % grid.nx, idx / grid.nx);
        let p = by_op.entry(op).or_insert(Problem {
            kind: ProblemKind::Gouge,
            operation: op,
            line: (line > 0).then_some(line),
            at: [c.x, c.y, stock],
            depth_mm: 0.0,
            volume_mm3: 0.0,
        });
        p.volume_mm3 += depth * area;
        if depth > p.depth_mm {
            p.depth_mm = depth;
            p.at = [c.x, c.y, stock];
            p.line = (line > 0).then_some(line);
        }
    }
    by_op.into_values().collect()
}

/// Holder collisions with the in-process stock, one per operation (the
/// deepest). The shank is judged on the replay itself (cuts above the
/// flutes), which sees the stock the program really leaves.
fn holder_collisions(plan: &Plan, k: &Knowledge, brep: &Brep) -> Vec<Problem> {
    let report = thinplan_collision::check(plan, k, brep);
    let mut by_op: BTreeMap<OperationId, Problem> = BTreeMap::new();
    for c in report
        .collisions
        .iter()
        .filter(|c| c.what == thinplan_collision::ToolPart::Holder)
    {
        let p = by_op.entry(c.operation).or_insert(Problem {
            kind: ProblemKind::HolderCollision,
            operation: Some(c.operation),
            line: None,
            at: c.position.to_array(),
            depth_mm: 0.0,
            volume_mm3: 0.0,
        });
        if c.penetration > p.depth_mm {
            p.depth_mm = c.penetration;
            p.at = c.position.to_array();
        }
    }
    by_op.into_values().collect()
}
