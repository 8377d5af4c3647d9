//! `cargo run -p thinplan-native --example inspect -- FILE.part.ron`: builds a
//! part and prints its faces, counts and volume.
fn main() {
    for arg in std::env::args().skip(1) {
        let path = std::path::Path::new(&arg);
        let part = match thinplan_native::load_part(path) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
        match part.build() {
            Ok(b) => {
                println!(
                    "{}: {} faces {:?}, {} edges, {} vertices, volume {:.6} (expected {:.6})",
                    part.name(),
                    b.faces.len(),
                    b.face_kind_counts(),
                    b.edges.len(),
                    b.vertices.len(),
                    thinplan_native::mass::volume(&b),
                    part.expected_volume()
                );
                for f in &b.faces {
                    println!(
                        "  {:<28} {:<8} loops {}",
                        f.name,
                        f.surface.kind_name(),
                        f.loops.len()
                    );
                }
            }
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        }
    }
}
