//! Stage 4: stiffness-feature sequence constraints (thesis §4.2.2–4.2.3,
//! §5.3.2, §6.2.1).
//!
//! Pair rules from `sequencing.ron` ([`SequencingKnowledge`]) are applied to
//! the whole part in priority order, highest first; within a rule, ordered
//! pairs `(first, second)` go by feature id. Each constraint a rule would
//! make is checked against those made so far (all from stronger rules or
//! earlier pairs of the same rule):
//!
//! - `Before` is **refused** when both features are already one
//!   simultaneous group, or when the second is already (transitively)
//!   before the first: it would close a cycle in the before-graph with
//!   simultaneous groups contracted. The refusal lists the cycle.
//!   It is **skipped** (not recorded) when the first is already before the
//!   second: it would add nothing.
//! - `Simultaneous` is refused when the two are already ordered either way
//!   (transitively), and skipped when they already are one group.
//! - `BeforeUnless(c)` is refused when `c` holds at that moment, else it is
//!   a `Before`.
//!
//! Every constraint carries provenance: `sequencing.<rule id>`, the rule's
//! priority and the values the condition used. [`order`] gives a
//! topological order honouring all constraints; [`try_add`] is the edit
//! API (a planner adding a constraint by hand).

use std::cmp::Reverse;
use std::collections::{BTreeMap, BTreeSet, BinaryHeap};

use glam::DVec3;
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::unionfind::UnionFind;
use petgraph::Direction;
use serde::{Deserialize, Serialize};
use thinplan_knowledge::{Knowledge, SequenceAction, SequencingKnowledge, SequencingRule};
use thinplan_plan::{
    Connection, ConnectionKind, Constraint, ConstraintKind, Plan, Provenance, ProvenanceSource,
    Refusal, Stage, StiffnessFeature, StiffnessFeatureId,
};

mod eval;
mod state;

use eval::{holds, Ctx, Facts, Values};
use state::{State, Step};

/// The prefix of the provenance rule of constraints made by sequencing rules.
pub const RULE_PREFIX: &str = "sequencing.";

/// The result of sequencing: constraints, refusals and simultaneous groups.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sequencing {
    /// In the order they were made (rule priority, then pair).
    pub constraints: Vec<Constraint<StiffnessFeatureId>>,
    /// Constraints rules would have made and did not, with why.
    pub refusals: Vec<Refusal>,
    /// Simultaneous groups of two or more features, each sorted, sorted by
    /// their first member.
    pub groups: Vec<Vec<StiffnessFeatureId>>,
}

impl Sequencing {
    /// The sequencing recorded in a plan: its stiffness constraints, the
    /// refusals of the sequence stage, and the groups they make.
    pub fn from_plan(plan: &Plan) -> Sequencing {
        let mut s = Sequencing {
            constraints: plan.stiffness_constraints.clone(),
            refusals: plan
                .refusals
                .iter()
                .filter(|r| r.stage == Stage::Sequence)
                .cloned()
                .collect(),
            groups: Vec::new(),
        };
        let mut uf = UnionFind::<usize>::new(plan.stiffness_features.len());
        let index: BTreeMap<StiffnessFeatureId, usize> = plan
            .stiffness_features
            .iter()
            .enumerate()
            .map(|(i, f)| (f.id, i))
            .collect();
        for c in &s.constraints {
            if let (ConstraintKind::Simultaneous, Some(&a), Some(&b)) =
                (c.kind, index.get(&c.first), index.get(&c.second))
            {
                uf.union(a, b);
            }
        }
        let mut by_rep: BTreeMap<usize, Vec<StiffnessFeatureId>> = BTreeMap::new();
        for (i, f) in plan.stiffness_features.iter().enumerate() {
            by_rep.entry(uf.find(i)).or_default().push(f.id);
        }
        s.groups = by_rep
            .into_values()
            .filter(|g| g.len() > 1)
            .map(|mut g| {
                g.sort();
                g
            })
            .collect();
        s.groups.sort();
        s
    }

    /// Writes the result into a plan: the results of this stage and every
    /// later one are dropped first ([`Plan::invalidate_from`]), then its
    /// constraints and refusals recorded and the stage listed as done.
    pub fn apply_to(self, plan: &mut Plan) {
        plan.invalidate_from(Stage::Sequence);
        plan.stiffness_constraints = self.constraints;
        plan.refusals.extend(self.refusals);
        plan.stages_done.push(Stage::Sequence);
    }
}

/// Runs the stage on a plan that has its features and connections.
pub fn run(plan: &Plan, knowledge: &Knowledge) -> Sequencing {
    sequence(
        &plan.stiffness_features,
        &plan.connections,
        plan.setup.up,
        &knowledge.sequencing,
    )
}

/// Applies the rules of `k` to every ordered pair of `features`; `up` is the
/// set-up's spindle axis (what "higher" means). Deterministic: the result
/// does not depend on the order of `features`, `connections` or the rules.
pub fn sequence(
    features: &[StiffnessFeature],
    connections: &[Connection],
    up: DVec3,
    k: &SequencingKnowledge,
) -> Sequencing {
    let up = up.try_normalize().unwrap_or(DVec3::Z);
    let mut sorted: Vec<&StiffnessFeature> = features.iter().collect();
    sorted.sort_by_key(|f| f.id);
    sorted.dedup_by_key(|f| f.id);
    let ids: Vec<StiffnessFeatureId> = sorted.iter().map(|f| f.id).collect();
    let index: BTreeMap<StiffnessFeatureId, usize> =
        ids.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    let facts: Vec<Facts> = sorted.iter().map(|f| Facts::of(f, up)).collect();
    let mut links: BTreeMap<(usize, usize), ConnectionKind> = BTreeMap::new();
    let mut leaves: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); ids.len()];
    for c in connections {
        let (Some(&b), Some(&l)) = (index.get(&c.base), index.get(&c.leaf)) else {
            continue;
        };
        if b == l {
            continue;
        }
        // One kind per pair: base–leaf wins over crossing (deterministic
        // whatever the input order).
        let e = links.entry((b, l)).or_insert(c.kind);
        if c.kind == ConnectionKind::BaseLeaf {
            *e = ConnectionKind::BaseLeaf;
        }
        if *e == ConnectionKind::BaseLeaf {
            leaves[b].insert(l);
        }
    }
    let leaves: Vec<Vec<usize>> = leaves
        .into_iter()
        .map(|s| s.into_iter().collect())
        .collect();

    let mut rules: Vec<&SequencingRule> = k.rules.iter().collect();
    rules.sort_by(|a, b| b.priority.cmp(&a.priority).then_with(|| a.id.cmp(&b.id)));

    let mut b = Builder::new(ids);
    for rule in rules {
        for a in 0..b.ids.len() {
            for c in 0..b.ids.len() {
                if a == c {
                    continue;
                }
                let cx = Ctx {
                    facts: &facts,
                    links: &links,
                    leaves: &leaves,
                    up,
                    state: &b.state,
                };
                if !holds(&rule.when, a, c, &cx, None) {
                    continue;
                }
                let mut values = Values::new();
                holds(&rule.when, a, c, &cx, Some(&mut values));
                let kind = match &rule.then {
                    SequenceAction::Before => ConstraintKind::Before,
                    SequenceAction::Simultaneous => ConstraintKind::Simultaneous,
                    SequenceAction::BeforeUnless(unless) => {
                        let mut uv = Values::new();
                        if holds(unless, a, c, &cx, Some(&mut uv)) {
                            values.extend(uv.into_iter().map(|(k, v)| (format!("unless.{k}"), v)));
                            let reason = format!(
                                "{} before {}: not applied, its unless-condition holds ({})",
                                b.ids[a],
                                b.ids[c],
                                show_values(&values)
                            );
                            b.refuse(rule_provenance(rule, values), a, c, reason, &[]);
                            continue;
                        }
                        values.extend(uv.into_iter().map(|(k, v)| (format!("unless.{k}"), v)));
                        ConstraintKind::Before
                    }
                };
                let constraint = Constraint {
                    first: b.ids[a],
                    second: b.ids[c],
                    kind,
                    priority: rule.priority,
                    provenance: rule_provenance(rule, values),
                };
                // Refusals are recorded by the builder; redundant ones skipped.
                let _ = b.apply(constraint, a, c, false);
            }
        }
    }
    b.finish()
}

fn rule_provenance(rule: &SequencingRule, values: Values) -> Provenance {
    let mut p = Provenance::new(
        ProvenanceSource::Knowledge,
        format!("{RULE_PREFIX}{}", rule.id),
    )
    .with_value("priority", f64::from(rule.priority));
    p.values.extend(values);
    p.note = rule.note.clone();
    p
}

fn show_values(v: &Values) -> String {
    v.iter()
        .map(|(k, x)| format!("{k} = {}", fmt_num(*x)))
        .collect::<Vec<_>>()
        .join(", ")
}

fn fmt_num(x: f64) -> String {
    let r = (x * 1000.0).round() / 1000.0;
    if r == r.trunc() && r.abs() < 1e15 {
        format!("{}", r as i64)
    } else {
        format!("{r}")
    }
}

/// The constraint number of a simultaneous link read from `groups`.
const GROUP: usize = usize::MAX - 1;

/// Outcome of applying one constraint.
enum Applied {
    Added,
    Redundant,
}

/// Constraints, refusals and the graph state being built.
struct Builder {
    ids: Vec<StiffnessFeatureId>,
    state: State,
    constraints: Vec<Constraint<StiffnessFeatureId>>,
    refusals: Vec<Refusal>,
}

impl Builder {
    fn new(ids: Vec<StiffnessFeatureId>) -> Self {
        let state = State::new(ids.len());
        Builder {
            ids,
            state,
            constraints: Vec::new(),
            refusals: Vec::new(),
        }
    }

    /// Checks and applies `c` (between indices `a` and `b`). With `keep`, a
    /// redundant constraint is still recorded (a planner's explicit edit).
    #[allow(clippy::result_large_err)] // a refusal is the plan's own record
    fn apply(
        &mut self,
        c: Constraint<StiffnessFeatureId>,
        a: usize,
        b: usize,
        keep: bool,
    ) -> Result<Applied, Refusal> {
        let (fa, fb) = (self.ids[a], self.ids[b]);
        let what = match c.kind {
            ConstraintKind::Before => format!("{fa} before {fb}"),
            ConstraintKind::Simultaneous => format!("{fa} simultaneous with {fb}"),
        };
        let conflict: Option<(String, Vec<Step>)> = if a == b {
            Some((
                "a feature cannot be sequenced against itself".into(),
                Vec::new(),
            ))
        } else {
            match c.kind {
                ConstraintKind::Before if self.state.same_group(a, b) => {
                    let path = self.state.together_path(a, b);
                    Some((
                        format!(
                            "{what} contradicts a stronger constraint: they are machined \
                             simultaneously ({})",
                            self.render(a, &path)
                        ),
                        path,
                    ))
                }
                ConstraintKind::Before if self.state.precedes(b, a) => {
                    let path = self.state.before_path(b, a);
                    let direct = matches!(path.as_slice(), [Step::Before { from, to, .. }]
                        if *from == b && *to == a);
                    let mut cycle = vec![Step::Before {
                        from: a,
                        to: b,
                        c: usize::MAX,
                    }];
                    cycle.extend(path.iter().copied());
                    let lead = if direct {
                        "reverses a stronger constraint and would close the cycle"
                    } else {
                        "would close the cycle"
                    };
                    Some((format!("{what} {lead} {}", self.render(a, &cycle)), cycle))
                }
                ConstraintKind::Simultaneous
                    if self.state.precedes(a, b) || self.state.precedes(b, a) =>
                {
                    let path = if self.state.precedes(a, b) {
                        self.state.before_path(a, b)
                    } else {
                        self.state.before_path(b, a)
                    };
                    let start = match path.first() {
                        Some(Step::Before { from, .. }) | Some(Step::Together { from, .. }) => {
                            *from
                        }
                        None => a,
                    };
                    Some((
                        format!(
                            "{what} contradicts a stronger constraint: they are already \
                             ordered ({})",
                            self.render(start, &path)
                        ),
                        path,
                    ))
                }
                _ => None,
            }
        };
        if let Some((reason, path)) = conflict {
            let r = self.refuse(c.provenance, a, b, reason, &path);
            return Err(r);
        }
        let redundant = match c.kind {
            ConstraintKind::Before => self.state.precedes(a, b),
            ConstraintKind::Simultaneous => self.state.same_group(a, b),
        };
        if redundant && !keep {
            return Ok(Applied::Redundant);
        }
        let n = self.constraints.len();
        match c.kind {
            ConstraintKind::Before => self.state.add_before(a, b, n),
            ConstraintKind::Simultaneous => self.state.add_together(a, b, n),
        }
        self.constraints.push(c);
        Ok(if redundant {
            Applied::Redundant
        } else {
            Applied::Added
        })
    }

    /// Records a refusal; `path` (explanation steps) is also written into
    /// the provenance values as `cycle.NN` = feature id, in order.
    fn refuse(
        &mut self,
        mut provenance: Provenance,
        a: usize,
        b: usize,
        reason: String,
        path: &[Step],
    ) -> Refusal {
        provenance
            .values
            .insert("first".into(), f64::from(self.ids[a].0));
        provenance
            .values
            .insert("second".into(), f64::from(self.ids[b].0));
        let mut nodes: Vec<usize> = Vec::new();
        for s in path {
            let (Step::Before { from, to, .. } | Step::Together { from, to, .. }) = *s;
            if nodes.last() != Some(&from) {
                nodes.push(from);
            }
            nodes.push(to);
        }
        for (i, n) in nodes.iter().enumerate() {
            provenance
                .values
                .insert(format!("cycle.{i:02}"), f64::from(self.ids[*n].0));
        }
        let r = Refusal {
            stage: Stage::Sequence,
            rule: provenance.rule.clone(),
            reason,
            provenance,
        };
        self.refusals.push(r.clone());
        r
    }

    /// `SF1 → SF2 (rule) ≡ SF3 (rule) …`, starting at `start`.
    fn render(&self, start: usize, path: &[Step]) -> String {
        let mut s = format!("{}", self.ids[start]);
        let rule = |c: usize| match self.constraints.get(c) {
            Some(x) => x.provenance.rule.clone(),
            None if c == GROUP => "its group".to_string(),
            None => "this rule".to_string(),
        };
        for step in path {
            match *step {
                Step::Before { to, c, .. } => {
                    s += &format!(" → {} ({})", self.ids[to], rule(c));
                }
                Step::Together { to, c, .. } => {
                    s += &format!(" ≡ {} (simultaneous, {})", self.ids[to], rule(c));
                }
            }
        }
        s
    }

    fn finish(self) -> Sequencing {
        let groups = self
            .state
            .groups()
            .into_iter()
            .map(|g| g.into_iter().map(|i| self.ids[i]).collect())
            .collect();
        Sequencing {
            constraints: self.constraints,
            refusals: self.refusals,
            groups,
        }
    }
}

/// Adds a constraint by hand (the GUI's edit): refused, with the cycle
/// listed, when it would close a cycle or contradict a simultaneous group;
/// otherwise recorded (even when already implied) and the groups updated.
/// The refusal is also appended to `s.refusals`. Assumes `s` is consistent
/// (as [`sequence`] and `try_add` leave it): existing constraints that are
/// not are ignored in the check.
#[allow(clippy::result_large_err)] // a refusal is the plan's own record, kept whole
pub fn try_add(s: &mut Sequencing, c: Constraint<StiffnessFeatureId>) -> Result<(), Refusal> {
    let mut ids: BTreeSet<StiffnessFeatureId> = BTreeSet::new();
    for x in &s.constraints {
        ids.insert(x.first);
        ids.insert(x.second);
    }
    ids.extend(s.groups.iter().flatten().copied());
    ids.insert(c.first);
    ids.insert(c.second);
    let ids: Vec<StiffnessFeatureId> = ids.into_iter().collect();
    let index: BTreeMap<StiffnessFeatureId, usize> =
        ids.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    let mut b = Builder::new(ids);
    for x in &s.constraints {
        let _ = b.apply(x.clone(), index[&x.first], index[&x.second], true);
    }
    for g in &s.groups {
        for w in g.windows(2) {
            let (i, j) = (index[&w[0]], index[&w[1]]);
            if !b.state.same_group(i, j) && !b.state.precedes(i, j) && !b.state.precedes(j, i) {
                b.state.add_together(i, j, GROUP);
            }
        }
    }
    b.refusals.clear();
    let (i, j) = (index[&c.first], index[&c.second]);
    let exists = s.constraints.iter().any(|x| {
        x.kind == c.kind
            && ((x.first, x.second) == (c.first, c.second)
                || (x.kind == ConstraintKind::Simultaneous
                    && (x.first, x.second) == (c.second, c.first)))
    });
    match b.apply(c.clone(), i, j, true) {
        Ok(_) => {
            if !exists {
                s.constraints.push(c);
            }
            s.groups = b
                .state
                .groups()
                .into_iter()
                .map(|g| g.into_iter().map(|i| b.ids[i]).collect())
                .collect();
            Ok(())
        }
        Err(r) => {
            s.refusals.push(r.clone());
            Err(r)
        }
    }
}

/// A machining order of `features` honouring every constraint of `s`:
/// simultaneous groups stay together (members by id), and among the groups
/// free to go next the one with the smallest id goes first. Should `s`
/// hold a cycle (a hand-edited plan), the smallest group on it is taken
/// first and the rest still follows the constraints where it can.
pub fn order(features: &[StiffnessFeature], s: &Sequencing) -> Vec<StiffnessFeatureId> {
    let mut ids: BTreeSet<StiffnessFeatureId> = features.iter().map(|f| f.id).collect();
    let wanted = ids.clone();
    for c in &s.constraints {
        ids.insert(c.first);
        ids.insert(c.second);
    }
    ids.extend(s.groups.iter().flatten().copied());
    let ids: Vec<StiffnessFeatureId> = ids.into_iter().collect();
    let index: BTreeMap<StiffnessFeatureId, usize> =
        ids.iter().enumerate().map(|(i, id)| (*id, i)).collect();
    let mut uf = UnionFind::<usize>::new(ids.len());
    for c in &s.constraints {
        if c.kind == ConstraintKind::Simultaneous {
            uf.union(index[&c.first], index[&c.second]);
        }
    }
    for g in &s.groups {
        for w in g.windows(2) {
            uf.union(index[&w[0]], index[&w[1]]);
        }
    }
    // One node per group, weighted by its smallest member (ids are sorted,
    // so the first member met is the smallest).
    let mut graph: DiGraph<usize, ()> = DiGraph::new();
    let mut node_of: BTreeMap<usize, NodeIndex> = BTreeMap::new();
    let mut members: BTreeMap<NodeIndex, Vec<usize>> = BTreeMap::new();
    for i in 0..ids.len() {
        let r = uf.find(i);
        let n = *node_of.entry(r).or_insert_with(|| graph.add_node(i));
        members.entry(n).or_default().push(i);
    }
    let mut edges = BTreeSet::new();
    for c in &s.constraints {
        if c.kind == ConstraintKind::Before {
            let (x, y) = (
                node_of[&uf.find(index[&c.first])],
                node_of[&uf.find(index[&c.second])],
            );
            if x != y && edges.insert((x, y)) {
                graph.add_edge(x, y, ());
            }
        }
    }
    let mut indegree: BTreeMap<NodeIndex, usize> = graph
        .node_indices()
        .map(|n| (n, graph.neighbors_directed(n, Direction::Incoming).count()))
        .collect();
    let mut ready: BinaryHeap<Reverse<(usize, NodeIndex)>> = indegree
        .iter()
        .filter(|(_, d)| **d == 0)
        .map(|(n, _)| Reverse((graph[*n], *n)))
        .collect();
    let mut done: BTreeSet<NodeIndex> = BTreeSet::new();
    let mut out = Vec::with_capacity(wanted.len());
    while done.len() < graph.node_count() {
        let n = match ready.pop() {
            Some(Reverse((_, n))) if !done.contains(&n) => n,
            Some(_) => continue,
            // A cycle: take the smallest group left.
            None => *indegree
                .keys()
                .filter(|n| !done.contains(n))
                .min_by_key(|n| graph[**n])
                .expect("nodes remain"),
        };
        done.insert(n);
        for &i in &members[&n] {
            if wanted.contains(&ids[i]) {
                out.push(ids[i]);
            }
        }
        for m in graph.neighbors_directed(n, Direction::Outgoing) {
            let d = indegree.get_mut(&m).expect("every node has a degree");
            *d = d.saturating_sub(1);
            if *d == 0 && !done.contains(&m) {
                ready.push(Reverse((graph[m], m)));
            }
        }
    }
    out
}
