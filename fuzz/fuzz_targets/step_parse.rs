#![no_main]
//! Reads arbitrary bytes as STEP with small limits: it must return, never
//! panic, hang or exhaust memory.

use libfuzzer_sys::fuzz_target;
use thinplan_step::{read_step_bytes, Limits};

fuzz_target!(|data: &[u8]| {
    let limits = Limits {
        max_bytes: 1 << 20,
        max_entities: 20_000,
        max_depth: 32,
        max_work: 2_000_000,
    };
    if let Ok(model) = read_step_bytes(data, &limits) {
        // Touch the result so that nothing is optimised away.
        let b = &model.brep;
        assert!(b.solids.len() + b.shells.len() > 0);
        for f in &b.faces {
            for &l in &f.loops {
                assert!(l < b.loops.len());
            }
        }
        for l in &b.loops {
            for c in &l.coedges {
                assert!(c.edge < b.edges.len());
            }
        }
        for e in &b.edges {
            assert!(e.start < b.vertices.len() && e.end < b.vertices.len());
        }
    }
});
