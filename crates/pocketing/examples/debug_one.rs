use thinplan_pocketing::bench::*;
use thinplan_pocketing::*;
fn main() {
    let name = std::env::args().nth(1).unwrap_or("circle".into());
    let l: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(100.0);
    for bp in bench_family(l) {
        if bp.pocket.name != name {
            continue;
        }
        let params = bench_params(&bp);
        let off = offset_path(&bp.pocket, &params).unwrap();
        let cur = curvilinear_path(&bp.pocket, &params).unwrap();
        println!("tool {} step {} | offset len {:.1} rings {} gap {:.3} | curv len {:.1} contours {} gap {:.3} {:?} {:?}",
            params.tool_diameter, params.stepover, off.length(), off.contours.len(), off.max_gap,
            cur.length(), cur.contours.len(), cur.max_gap, cur.method, cur.fallback_reason);
        println!("choice: {:?}", cur.choice);
        if let Some(c) = cur.center {
            for (k, ct) in cur.contours.iter().enumerate() {
                let rmin = ct
                    .iter()
                    .map(|p| p.distance(c))
                    .fold(f64::INFINITY, f64::min);
                let rmax = ct.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
                println!("  contour {k}: n {} r {:.2}..{:.2}", ct.len(), rmin, rmax);
            }
        }
        std::fs::write(format!("/tmp/pk_{name}.svg"), pocket_svg(&bp.pocket, &cur)).unwrap();
        std::fs::write(
            format!("/tmp/pk_{name}_off.svg"),
            pocket_svg(&bp.pocket, &off),
        )
        .unwrap();
    }
}
