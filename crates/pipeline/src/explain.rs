//! Why the plan is as it is (`thinplan explain PLAN ID [ID]`): the
//! provenance of a stiffness feature, machining feature or operation with
//! every constraint and refusal that names it; for two ids, the constraint
//! between them or the chain of constraints that orders them. A function
//! of the saved plan alone, so a planner can ask about any plan file.

use std::collections::{BTreeMap, VecDeque};

use serde_json::{json, Value};
use thinplan_plan::{
    Constraint, ConstraintKind, MachiningFeatureId, OperationId, Plan, Provenance,
    StiffnessFeatureId,
};

/// Something in the plan an explanation is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Subject {
    Stiffness(StiffnessFeatureId),
    Machining(MachiningFeatureId),
    Operation(OperationId),
}

impl std::fmt::Display for Subject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Subject::Stiffness(i) => i.fmt(f),
            Subject::Machining(i) => i.fmt(f),
            Subject::Operation(i) => i.fmt(f),
        }
    }
}

/// Reads `SF3`, `MF12` or `OP4` (any case) and checks the plan has it.
pub fn parse_subject(plan: &Plan, text: &str) -> Result<Subject, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let (prefix, digits) = upper.split_at(upper.len().min(2));
    let n: u32 = digits.parse().map_err(|_| {
        format!("`{t}` is not an id: expected SF<n> (stiffness feature), MF<n> (machining feature) or OP<n> (operation)")
    })?;
    let subject = match prefix {
        "SF" => Subject::Stiffness(StiffnessFeatureId(n)),
        "MF" => Subject::Machining(MachiningFeatureId(n)),
        "OP" => Subject::Operation(OperationId(n)),
        _ => {
            return Err(format!(
                "`{t}` is not an id: expected SF<n>, MF<n> or OP<n>"
            ))
        }
    };
    let exists = match subject {
        Subject::Stiffness(i) => plan.stiffness_features.iter().any(|f| f.id == i),
        Subject::Machining(i) => plan.machining_features.iter().any(|f| f.id == i),
        Subject::Operation(i) => plan.operations.iter().any(|o| o.id == i),
    };
    if exists {
        Ok(subject)
    } else {
        Err(format!(
            "the plan has no {subject} (it has {} stiffness features, {} machining features, {} operations)",
            plan.stiffness_features.len(),
            plan.machining_features.len(),
            plan.operations.len()
        ))
    }
}

fn provenance_json(p: &Provenance) -> Value {
    json!({
        "source": format!("{:?}", p.source).to_lowercase(),
        "rule": p.rule,
        "values": p.values,
        "note": p.note,
    })
}

fn constraint_json<Id: std::fmt::Display>(c: &Constraint<Id>) -> Value {
    json!({
        "first": c.first.to_string(),
        "then": c.second.to_string(),
        "kind": match c.kind {
            ConstraintKind::Before => "before",
            ConstraintKind::Simultaneous => "simultaneous",
        },
        "priority": c.priority,
        "provenance": provenance_json(&c.provenance),
    })
}

/// Refusals whose reason names `id` as a whole word.
fn refusals_naming(plan: &Plan, id: &str) -> Vec<Value> {
    plan.refusals
        .iter()
        .filter(|r| {
            r.reason
                .split(|c: char| !c.is_ascii_alphanumeric())
                .any(|w| w == id)
                || r.provenance.note == id
        })
        .map(|r| {
            json!({
                "stage": format!("{:?}", r.stage).to_lowercase(),
                "rule": r.rule,
                "reason": r.reason,
                "provenance": provenance_json(&r.provenance),
            })
        })
        .collect()
}

/// The explanation of one subject as JSON: what it is, its provenance, and
/// every constraint and refusal naming it.
pub fn explain(plan: &Plan, s: Subject) -> Value {
    let name = s.to_string();
    let mut v = match s {
        Subject::Stiffness(id) => {
            let f = plan.stiffness_features.iter().find(|f| f.id == id);
            json!({
                "id": name,
                "what": "stiffness feature",
                "kind": f.map(|f| format!("{:?}", f.kind).to_lowercase()),
                "role": f.and_then(|f| f.role).map(|r| format!("{r:?}").to_lowercase()),
                "provenance": f.map(|f| provenance_json(&f.provenance)),
                "connections": plan.connections.iter()
                    .filter(|c| c.base == id || c.leaf == id)
                    .map(|c| json!({
                        "base": c.base.to_string(),
                        "leaf": c.leaf.to_string(),
                        "kind": format!("{:?}", c.kind).to_lowercase(),
                        "provenance": provenance_json(&c.provenance),
                    }))
                    .collect::<Vec<_>>(),
                "constraints": plan.stiffness_constraints.iter()
                    .filter(|c| c.first == id || c.second == id)
                    .map(constraint_json)
                    .collect::<Vec<_>>(),
                "machining_features": plan.machining_features.iter()
                    .filter(|m| m.owner == id)
                    .map(|m| m.id.to_string())
                    .collect::<Vec<_>>(),
            })
        }
        Subject::Machining(id) => {
            let f = plan.machining_features.iter().find(|f| f.id == id);
            json!({
                "id": name,
                "what": "machining feature",
                "owner": f.map(|f| f.owner.to_string()),
                "provenance": f.map(|f| provenance_json(&f.provenance)),
                "constraints": plan.machining_constraints.iter()
                    .filter(|c| c.first == id || c.second == id)
                    .map(constraint_json)
                    .collect::<Vec<_>>(),
                "operations": plan.operations.iter()
                    .filter(|o| o.feature == id)
                    .map(|o| o.id.to_string())
                    .collect::<Vec<_>>(),
            })
        }
        Subject::Operation(id) => {
            let o = plan.operations.iter().find(|o| o.id == id);
            json!({
                "id": name,
                "what": "operation",
                "feature": o.map(|o| o.feature.to_string()),
                "method": o.map(|o| o.method.clone()),
                "tool": o.map(|o| o.tool.clone()),
                "place_in_order": plan.operation_order.iter().position(|x| *x == id).map(|i| i + 1),
                "provenance": o.map(|o| provenance_json(&o.provenance)),
            })
        }
    };
    v["refusals"] = Value::Array(refusals_naming(plan, &name));
    v
}

/// The shortest chain of constraints from `a` to `b` over the given edges
/// (breadth-first, smallest id first), each step's constraint included.
fn chain<Id: Copy + Ord>(
    constraints: &[Constraint<Id>],
    a: Id,
    b: Id,
    both_ways_if_simultaneous: bool,
) -> Option<Vec<&Constraint<Id>>> {
    let mut succ: BTreeMap<Id, Vec<(Id, &Constraint<Id>)>> = BTreeMap::new();
    for c in constraints {
        succ.entry(c.first).or_default().push((c.second, c));
        if both_ways_if_simultaneous && c.kind == ConstraintKind::Simultaneous {
            succ.entry(c.second).or_default().push((c.first, c));
        }
    }
    let mut came: BTreeMap<Id, (Id, &Constraint<Id>)> = BTreeMap::new();
    let mut queue = VecDeque::from([a]);
    while let Some(x) = queue.pop_front() {
        if x == b {
            let mut out = Vec::new();
            let mut y = b;
            while y != a {
                let (p, c) = came[&y];
                out.push(c);
                y = p;
            }
            out.reverse();
            return Some(out);
        }
        for &(y, c) in succ.get(&x).map(Vec::as_slice).unwrap_or(&[]) {
            if y != a && !came.contains_key(&y) {
                came.insert(y, (x, c));
                queue.push_back(y);
            }
        }
    }
    None
}

/// Why two features are ordered as they are: the chain of constraints that
/// puts the first before the second (or the second before the first), or
/// that none does. Both must be stiffness features or both machining
/// features.
pub fn explain_pair(plan: &Plan, a: Subject, b: Subject) -> Result<Value, String> {
    let (fwd, back): (Option<Vec<Value>>, Option<Vec<Value>>) = match (a, b) {
        (Subject::Stiffness(x), Subject::Stiffness(y)) => (
            chain(&plan.stiffness_constraints, x, y, true)
                .map(|c| c.into_iter().map(constraint_json).collect()),
            chain(&plan.stiffness_constraints, y, x, true)
                .map(|c| c.into_iter().map(constraint_json).collect()),
        ),
        (Subject::Machining(x), Subject::Machining(y)) => (
            chain(&plan.machining_constraints, x, y, false)
                .map(|c| c.into_iter().map(constraint_json).collect()),
            chain(&plan.machining_constraints, y, x, false)
                .map(|c| c.into_iter().map(constraint_json).collect()),
        ),
        _ => {
            return Err(format!(
                "{a} and {b}: an order is explained between two stiffness features or two machining features"
            ))
        }
    };
    let verdict = match (&fwd, &back) {
        (Some(_), Some(_)) => "simultaneous",
        (Some(_), None) => "first_before_second",
        (None, Some(_)) => "second_before_first",
        (None, None) => "unordered",
    };
    Ok(json!({
        "first": a.to_string(),
        "second": b.to_string(),
        "order": verdict,
        "chain": fwd.or(back).unwrap_or_default(),
        "refusals": refusals_naming(plan, &a.to_string())
            .into_iter()
            .filter(|r| r["reason"].as_str().is_some_and(|t| {
                t.split(|c: char| !c.is_ascii_alphanumeric()).any(|w| w == b.to_string())
            }))
            .collect::<Vec<_>>(),
    }))
}

fn provenance_lines(out: &mut String, indent: &str, p: &Value) {
    use std::fmt::Write as _;
    let _ = writeln!(
        out,
        "{indent}by {} ({})",
        p["rule"].as_str().unwrap_or(""),
        p["source"].as_str().unwrap_or("")
    );
    if let Some(note) = p["note"].as_str().filter(|n| !n.is_empty()) {
        let _ = writeln!(out, "{indent}  {note}");
    }
    if let Some(values) = p["values"].as_object().filter(|v| !v.is_empty()) {
        let list: Vec<String> = values.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        let _ = writeln!(out, "{indent}  values: {}", list.join(", "));
    }
}

fn constraint_line(out: &mut String, c: &Value) {
    use std::fmt::Write as _;
    let _ = writeln!(
        out,
        "  {} {} {} (priority {})",
        c["first"].as_str().unwrap_or(""),
        if c["kind"] == "simultaneous" {
            "with"
        } else {
            "before"
        },
        c["then"].as_str().unwrap_or(""),
        c["priority"]
    );
    provenance_lines(out, "    ", &c["provenance"]);
}

/// The explanation as text for a terminal.
pub fn explain_text(v: &Value) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    if v.get("order").is_some() {
        let (a, b) = (
            v["first"].as_str().unwrap_or(""),
            v["second"].as_str().unwrap_or(""),
        );
        let _ = writeln!(
            out,
            "{}",
            match v["order"].as_str().unwrap_or("") {
                "first_before_second" => format!("{a} comes before {b}, because:"),
                "second_before_first" => format!("{b} comes before {a}, because:"),
                "simultaneous" => format!("{a} and {b} are machined together, because:"),
                _ => format!("no constraint orders {a} and {b}; the planner is free to choose"),
            }
        );
        for c in v["chain"].as_array().into_iter().flatten() {
            constraint_line(&mut out, c);
        }
    } else {
        let mut head = format!(
            "{} ({})",
            v["id"].as_str().unwrap_or(""),
            v["what"].as_str().unwrap_or("")
        );
        for key in ["kind", "role", "owner", "feature", "method", "tool"] {
            if let Some(t) = v[key].as_str() {
                let _ = write!(head, ", {key} {t}");
            }
        }
        if let Some(k) = v["place_in_order"].as_u64() {
            let _ = write!(head, ", place {k} in the operation order");
        }
        let _ = writeln!(out, "{head}");
        provenance_lines(&mut out, "  ", &v["provenance"]);
        for (key, title) in [
            ("connections", "connections"),
            ("constraints", "constraints"),
        ] {
            let list = v[key].as_array().cloned().unwrap_or_default();
            if list.is_empty() {
                continue;
            }
            let _ = writeln!(out, "{title}:");
            for c in &list {
                if key == "connections" {
                    let _ = writeln!(
                        out,
                        "  {} carries {} ({})",
                        c["base"].as_str().unwrap_or(""),
                        c["leaf"].as_str().unwrap_or(""),
                        c["kind"].as_str().unwrap_or("")
                    );
                    provenance_lines(&mut out, "    ", &c["provenance"]);
                } else {
                    constraint_line(&mut out, c);
                }
            }
        }
        for key in ["machining_features", "operations"] {
            let list: Vec<&str> = v[key]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(Value::as_str)
                .collect();
            if !list.is_empty() {
                let _ = writeln!(out, "{}: {}", key.replace('_', " "), list.join(" "));
            }
        }
    }
    for r in v["refusals"].as_array().into_iter().flatten() {
        let _ = writeln!(
            out,
            "refused ({}, {}): {}",
            r["stage"].as_str().unwrap_or(""),
            r["rule"].as_str().unwrap_or(""),
            r["reason"].as_str().unwrap_or("")
        );
    }
    out
}
