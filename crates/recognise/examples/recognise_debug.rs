//! Prints what recognition finds on sample parts or STEP files (debug aid).
use glam::DVec3;
fn main() {
    let k = thinplan_knowledge::Knowledge::builtin().unwrap();
    let m = k.machines["hsm_5axis"].clone();
    for p in std::env::args().skip(1) {
        let path = std::path::Path::new(&p);
        let brep = if p.ends_with(".step") || p.ends_with(".stp") {
            thinplan_step::read_step_file(path).unwrap().brep
        } else {
            thinplan_native::load_part(path).unwrap().build().unwrap()
        };
        let t = std::time::Instant::now();
        let r = thinplan_recognise::recognise(
            &brep,
            if std::env::var("DOWN").is_ok() {
                -DVec3::Z
            } else {
                DVec3::Z
            },
            &k,
            &m,
        );
        println!("== {p}: {} faces, {:?}", brep.faces.len(), t.elapsed());
        for f in &r.features {
            let names: Vec<&str> = f
                .faces
                .iter()
                .map(|&i| brep.faces[i].name.as_str())
                .collect();
            println!(
                "  {} {:?} {:?} t={:?} h={:.2} l={:.2} axis={:?} rule={} {:?}",
                f.id,
                f.kind,
                f.role,
                f.thickness,
                f.height,
                f.length,
                f.axis,
                f.provenance.rule,
                names
            );
        }
        for c in &r.connections {
            println!(
                "  {} -> {} {:?} ({})",
                c.base, c.leaf, c.kind, c.provenance.rule
            );
        }
        if let Ok(dir) = std::env::var("SVG_DIR") {
            let name = std::path::Path::new(&p)
                .file_stem()
                .unwrap()
                .to_string_lossy()
                .to_string();
            std::fs::write(
                format!("{dir}/{name}.svg"),
                thinplan_recognise::report::to_svg(&r, &brep),
            )
            .unwrap();
            std::fs::write(
                format!("{dir}/{name}.json"),
                serde_json::to_string_pretty(&thinplan_recognise::report::to_json(&r, &brep))
                    .unwrap(),
            )
            .unwrap();
        }
        for w in &r.warnings {
            println!("  warning: {w}");
        }
    }
}
