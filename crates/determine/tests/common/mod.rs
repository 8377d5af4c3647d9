//! Helpers shared by stage 5's test files: the stages up to determine on a
//! sample, and order and geometry read back independently of the code under
//! test.
#![allow(dead_code)]

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;
use thinplan_brep::Brep;
use thinplan_determine::{determine, prism_points, Determination};
use thinplan_knowledge::Knowledge;
use thinplan_plan::{
    MachiningFeature, MachiningFeatureId, Plan, Provenance, ProvenanceSource, Setup, Stage,
};

/// Import, set-up, recognise, connect and sequence a sample, then determine.
pub fn planned(name: &str, k: &Knowledge) -> (Plan, Brep, Determination) {
    let imported = thinplan_import::import(&format!("builtin:{name}")).expect("imports");
    let setup = Setup {
        up: DVec3::Z,
        machine: thinplan_knowledge::DEFAULT_MACHINE.into(),
        tool_set: thinplan_knowledge::DEFAULT_TOOL_SET.into(),
        material: thinplan_knowledge::DEFAULT_MATERIAL.into(),
        provenance: Provenance::new(ProvenanceSource::Default, "test"),
    };
    let mut plan = Plan::new(imported.part, setup);
    let machine = k.machine(&plan.setup.machine).unwrap();
    let r = thinplan_recognise::recognise(&imported.brep, plan.setup.up, k, machine);
    plan.stiffness_features = r.features;
    plan.connections = r.connections;
    plan.stages_done.extend([Stage::Recognise, Stage::Connect]);
    thinplan_sequence::run(&plan, k).apply_to(&mut plan);
    let d = determine(&plan, &imported.brep, k).expect("determines");
    (plan, imported.brep, d)
}

/// A provenance value, with the feature named when it is missing.
pub fn v(f: &MachiningFeature, name: &str) -> f64 {
    *f.provenance
        .values
        .get(name)
        .unwrap_or_else(|| panic!("{} has no `{name}`: {:?}", f.id, f.provenance))
}

/// The z extent of a feature, from its prism's corners.
pub fn z_span(f: &MachiningFeature) -> (f64, f64) {
    prism_points(&f.shape)
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.z), hi.max(p.z))
        })
}

/// Every feature's successors by a path of `Before` constraints (my own
/// depth-first search from each feature).
pub struct Reach(BTreeMap<MachiningFeatureId, BTreeSet<MachiningFeatureId>>);

impl Reach {
    pub fn of(d: &Determination) -> Reach {
        let mut succ: BTreeMap<MachiningFeatureId, Vec<MachiningFeatureId>> = BTreeMap::new();
        for c in &d.constraints {
            succ.entry(c.first).or_default().push(c.second);
        }
        let mut all = BTreeMap::new();
        for f in &d.features {
            let mut seen = BTreeSet::new();
            let mut stack = vec![f.id];
            while let Some(x) = stack.pop() {
                for &y in succ.get(&x).map(Vec::as_slice).unwrap_or(&[]) {
                    if seen.insert(y) {
                        stack.push(y);
                    }
                }
            }
            all.insert(f.id, seen);
        }
        Reach(all)
    }

    /// `a` is machined before `b`.
    pub fn precedes(&self, a: MachiningFeatureId, b: MachiningFeatureId) -> bool {
        self.0.get(&a).is_some_and(|s| s.contains(&b))
    }
}

pub fn precedes(d: &Determination, a: MachiningFeatureId, b: MachiningFeatureId) -> bool {
    Reach::of(d).precedes(a, b)
}

pub fn by_rule<'a>(d: &'a Determination, rule: &str) -> Vec<&'a MachiningFeature> {
    d.features
        .iter()
        .filter(|f| f.provenance.rule == rule)
        .collect()
}
