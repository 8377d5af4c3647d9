//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::PathBuf;

use thinplan_brep::Brep;

pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// Checks the structural invariants every read must give; returns a list of
/// problems (empty when fine).
pub fn check_brep(b: &Brep) -> Vec<String> {
    let mut problems = Vec::new();
    for (fi, f) in b.faces.iter().enumerate() {
        if f.loops.is_empty() {
            problems.push(format!("face {fi} has no loop"));
        }
        for &l in &f.loops {
            let Some(lp) = b.loops.get(l) else {
                problems.push(format!("face {fi}: loop {l} out of range"));
                continue;
            };
            let n = lp.coedges.len();
            if n == 0 && lp.vertex.is_none() {
                problems.push(format!("face {fi}: empty loop {l}"));
            }
            for i in 0..n {
                let a = lp.coedges[i];
                let c = lp.coedges[(i + 1) % n];
                if b.coedge_end(a) != b.coedge_start(c) {
                    problems.push(format!("face {fi}: loop {l} is not a closed chain at {i}"));
                }
            }
        }
    }
    for (si, s) in b.shells.iter().enumerate() {
        if !s.closed {
            continue;
        }
        let mut uses: HashMap<usize, usize> = HashMap::new();
        for &f in &s.faces {
            for &l in &b.faces[f].loops {
                for ce in &b.loops[l].coedges {
                    *uses.entry(ce.edge).or_default() += 1;
                }
            }
        }
        for (e, n) in uses {
            if n != 2 {
                problems.push(format!("shell {si}: edge {e} used by {n} coedges"));
            }
        }
    }
    problems
}
