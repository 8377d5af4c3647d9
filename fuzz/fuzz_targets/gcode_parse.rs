//! `thinplan_stocksim::parse_bytes` on arbitrary bytes must return Ok or Err,
//! never panic; a program that reads is replayed on a small Z-map too.
#![no_main]

use libfuzzer_sys::fuzz_target;
use thinplan_stocksim::{parse_bytes, Blank, ToolLibrary, ToolShape, ZMap};

fuzz_target!(|data: &[u8]| {
    if let Ok(p) = parse_bytes(data, "fuzz.ngc") {
        // Keep the replay small: a coarse grid, bounded moves.
        if p.moves.len() <= 200 {
            let blank = Blank {
                min: glam::DVec3::new(0.0, 0.0, 0.0),
                max: glam::DVec3::new(50.0, 50.0, 20.0),
            };
            if let Ok(mut z) = ZMap::new(blank, 1.0) {
                let tools: ToolLibrary = (0..100).map(|t| (t, ToolShape::bull(6.0, 1.0))).collect();
                let _ = z.replay(&p, &tools);
            }
        }
    }
});
