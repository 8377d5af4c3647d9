//! The short report `thinplan plan` ends with: the verdict, the set-up, the
//! tools, operations and time, the material left and why, and warnings
//! grouped by kind (every one with `--verbose`, and always in `--json`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use thinplan_knowledge::Knowledge;
use thinplan_plan::{Plan, Verdict};

pub fn summary(
    source: &str,
    plan: &Plan,
    k: &Knowledge,
    warnings: &[String],
    verbose: bool,
) -> String {
    let mut s = String::new();
    let p = &plan.part.summary;
    let _ = writeln!(
        s,
        "planned {source} ({} solid(s), {} faces, {:.1} mm3)",
        p.solids, p.faces, p.volume
    );
    let st = &plan.setup;
    let _ = writeln!(
        s,
        "  set-up   up ({:.3}, {:.3}, {:.3}), machine {}, tools {}, material {}",
        st.up.x, st.up.y, st.up.z, st.machine, st.tool_set, st.material
    );
    let _ = writeln!(
        s,
        "  features {} stiffness, {} machining; {} refusal(s)",
        plan.stiffness_features.len(),
        plan.machining_features.len(),
        plan.refusals.len()
    );
    operations(&mut s, plan, k);
    verification(&mut s, plan);
    grouped_warnings(&mut s, warnings, verbose);
    s
}

fn operations(s: &mut String, plan: &Plan, k: &Knowledge) {
    if plan.operation_order.is_empty() {
        let _ = writeln!(s, "  program  no operations");
        return;
    }
    let by_id: BTreeMap<_, _> = plan.operations.iter().map(|o| (o.id, o)).collect();
    let mut tools: Vec<&str> = Vec::new();
    let mut time = 0.0;
    for id in &plan.operation_order {
        if let Some(op) = by_id.get(id) {
            if !tools.contains(&op.tool.as_str()) {
                tools.push(&op.tool);
            }
            time += thinplan_operations::summary(op).time_s;
        }
    }
    let set = k.tool_set(&plan.setup.tool_set);
    let named: Vec<String> = tools
        .iter()
        .map(|t| {
            set.and_then(|s| s.tools.iter().find(|x| x.id == *t))
                .map_or_else(|| t.to_string(), |x| format!("{t} (Ø{})", x.diameter))
        })
        .collect();
    let _ = writeln!(
        s,
        "  program  {} operation(s), tools {}, machining time {:.1} min",
        plan.operation_order.len(),
        named.join(", "),
        time / 60.0
    );
}

fn verification(s: &mut String, plan: &Plan) {
    let Some(v) = &plan.verification else {
        let _ = writeln!(
            s,
            "  verdict  not verified (planning stopped before stage 9)"
        );
        return;
    };
    let _ = writeln!(
        s,
        "  verdict  {} (replayed {} time(s) on a {} mm Z-map)",
        v.verdict.name().to_uppercase(),
        v.rounds,
        v.cell_mm
    );
    for l in &v.left {
        let at =
            l.at.map(|a| format!(" at ({:.1}, {:.1})", a[0], a[1]))
                .unwrap_or_default();
        let _ = writeln!(
            s,
            "  left     {:.2} mm3 {} in {} patch(es), thickest {:.2} mm{at}",
            l.volume_mm3,
            l.reason.name(),
            l.patches,
            l.worst_mm
        );
    }
    if !v.removed.is_empty() {
        let mut kinds: BTreeMap<&str, Vec<String>> = BTreeMap::new();
        for r in &v.removed {
            kinds
                .entry(r.problem.kind.name())
                .or_default()
                .push(r.operation.to_string());
        }
        for (kind, ops) in kinds {
            let _ = writeln!(
                s,
                "  removed  {} operation(s) for a {kind}: {}",
                ops.len(),
                ops.join(" ")
            );
        }
    }
    if v.verdict == Verdict::Unsafe {
        for p in v.problems.iter().take(10) {
            let _ = writeln!(
                s,
                "  problem  {} by {} at ({:.2}, {:.2}, {:.2}), {:.3} mm, {:.2} mm3{}",
                p.kind.name(),
                p.operation
                    .map_or_else(|| "no operation".to_string(), |o| o.to_string()),
                p.at[0],
                p.at[1],
                p.at[2],
                p.depth_mm,
                p.volume_mm3,
                p.line.map(|l| format!(" (line {l})")).unwrap_or_default()
            );
        }
        if v.problems.len() > 10 {
            let _ = writeln!(s, "  problem  … {} more in --json", v.problems.len() - 10);
        }
        let _ = writeln!(s, "  no program is written for an unsafe plan");
    }
}

/// A warning's kind: its text with ids and numbers blanked.
fn kind_of(w: &str) -> String {
    let mut out = String::new();
    let mut last_hash = false;
    let mut chars = w.chars().peekable();
    while let Some(c) = chars.next() {
        let number = c.is_ascii_digit()
            || (c == '.' && last_hash)
            || (c == '-' && chars.peek().is_some_and(|d| d.is_ascii_digit()));
        if number {
            if !last_hash {
                out.push('#');
            }
        } else {
            out.push(c);
        }
        last_hash = number;
    }
    out
}

fn grouped_warnings(s: &mut String, warnings: &[String], verbose: bool) {
    if warnings.is_empty() {
        return;
    }
    if verbose {
        for w in warnings {
            let _ = writeln!(s, "warning: {w}");
        }
        return;
    }
    let mut groups: BTreeMap<String, (usize, &str)> = BTreeMap::new();
    for w in warnings {
        groups.entry(kind_of(w)).or_insert((0, w)).0 += 1;
    }
    let mut list: Vec<_> = groups.into_values().collect();
    list.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(b.1)));
    let _ = writeln!(
        s,
        "  warnings {} in {} kind(s) (all with --verbose or --json):",
        warnings.len(),
        list.len()
    );
    for (n, example) in list {
        let _ = writeln!(s, "    {n:>4} × {example}");
    }
}

/// One line per stage with its wall time, from the instants each began and
/// the instant the last one ended.
pub fn stage_times(starts: &[(String, std::time::Instant)], end: std::time::Instant) -> String {
    let mut out = String::from("stage times:");
    for (i, (name, start)) in starts.iter().enumerate() {
        let next = starts.get(i + 1).map_or(end, |(_, t)| *t);
        out.push_str(&format!(" {name} {:.2} s;", (next - *start).as_secs_f64()));
    }
    out.push_str(&format!(
        " total {:.2} s\n",
        starts
            .first()
            .map_or(0.0, |(_, t)| (end - *t).as_secs_f64())
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::kind_of;

    #[test]
    fn warnings_that_differ_in_ids_and_numbers_are_one_kind() {
        let a = kind_of("MF13: a boundary pass starting at (111.00, 108.00) has no room");
        let b = kind_of("MF4: a boundary pass starting at (-2.5, 7) has no room");
        assert_eq!(a, b);
        assert_ne!(a, kind_of("MF4: the shank rubs"));
    }
}
