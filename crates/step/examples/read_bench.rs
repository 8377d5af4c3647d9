//! Reads every `.step`/`.stp` file of a directory N times and prints the
//! throughput of the parser alone and of the whole read (parse + B-rep).
//!
//! ```text
//! cargo run --release -p thinplan-step --example read_bench -- /work/shared/data/mfcad 5
//! ```

use std::path::PathBuf;
use std::time::{Duration, Instant};

use thinplan_step::{p21, read_step_bytes, Limits};

fn main() {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "/work/shared/data/mfcad".into()),
    );
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(3);
    let mut files: Vec<PathBuf> = match std::fs::read_dir(&dir) {
        Ok(rd) => rd
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "step" | "stp"))
            })
            .collect(),
        Err(e) => {
            eprintln!("cannot read {}: {e}", dir.display());
            std::process::exit(2);
        }
    };
    files.sort();
    let data: Vec<(PathBuf, Vec<u8>)> = files
        .into_iter()
        .filter_map(|p| std::fs::read(&p).ok().map(|b| (p, b)))
        .collect();
    let bytes: usize = data.iter().map(|(_, b)| b.len()).sum();
    let limits = Limits::default();
    let plimits = p21::ParseLimits {
        max_bytes: limits.max_bytes,
        max_entities: limits.max_entities,
        max_depth: limits.max_depth,
    };
    let (mut t_parse, mut t_read) = (Duration::ZERO, Duration::ZERO);
    let (mut faces, mut errors) = (0usize, 0usize);
    for _ in 0..n {
        for (path, b) in &data {
            let t = Instant::now();
            let ok = p21::parse(b, plimits).is_ok();
            t_parse += t.elapsed();
            if !ok {
                errors += 1;
            }
            let t = Instant::now();
            match read_step_bytes(b, &limits) {
                Ok(m) => faces += m.brep.faces.len(),
                Err(e) => {
                    errors += 1;
                    eprintln!("{}: {e}", path.display());
                }
            }
            t_read += t.elapsed();
        }
    }
    let mb = (bytes * n) as f64 / 1e6;
    println!(
        "{} files, {:.2} MB x {n} = {mb:.2} MB, {errors} errors",
        data.len(),
        bytes as f64 / 1e6
    );
    println!(
        "parse only : {:.3} s, {:.1} MB/s",
        t_parse.as_secs_f64(),
        mb / t_parse.as_secs_f64()
    );
    println!(
        "full read  : {:.3} s, {:.1} MB/s, {:.0} faces/s ({faces} faces)",
        t_read.as_secs_f64(),
        mb / t_read.as_secs_f64(),
        faces as f64 / t_read.as_secs_f64()
    );
}
