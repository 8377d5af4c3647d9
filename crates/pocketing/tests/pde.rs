//! FEM checks on the disk: −Δu = 1 against (R² − r²)/4, λ₁ against j₀,₁².

use glam::DVec2;
use thinplan_pocketing::fem::{solve, Field, Mesh};

fn disk(r: f64, n: usize) -> Vec<DVec2> {
    (0..n)
        .map(|i| r * DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64))
        .collect()
}

fn poisson_error(h: f64) -> (f64, usize) {
    let r = 1.0;
    let b = disk(r, (std::f64::consts::TAU / h).ceil() as usize);
    let mesh = Mesh::of_loop(&b, h).unwrap();
    let sol = solve(&mesh, Field::Poisson).unwrap();
    let mut err: f64 = 0.0;
    for (p, u) in mesh.vertices.iter().zip(&sol.raw) {
        let exact = (r * r - p.length_squared()) / 4.0;
        err = err.max((u - exact).abs());
    }
    (err, mesh.vertices.len())
}

#[test]
fn poisson_on_disk_matches_analytic_and_converges() {
    let (e1, n1) = poisson_error(0.1);
    let (e2, n2) = poisson_error(0.05);
    let (e3, n3) = poisson_error(0.025);
    eprintln!("h=0.1: {e1:.2e} ({n1} v); 0.05: {e2:.2e} ({n2} v); 0.025: {e3:.2e} ({n3} v)");
    // the polygonal boundary loses O(h²) of the radius; u_max = 0.25
    assert!(e3 < 2e-3, "max error {e3}");
    assert!(e2 < e1 && e3 < e2, "no convergence: {e1} {e2} {e3}");
    assert!(e1 / e3 > 6.0, "expected ~O(h²): {e1} / {e3}");
}

#[test]
fn principal_eigenvalue_of_unit_disk() {
    let b = disk(1.0, 200);
    let mesh = Mesh::of_loop(&b, 0.035).unwrap();
    let sol = solve(&mesh, Field::Eigen).unwrap();
    let lam = sol.eigenvalue.unwrap();
    let exact = 2.404_825_557_695_773f64.powi(2); // j₀,₁²
    eprintln!(
        "λ₁ = {lam} (exact {exact}), {} vertices",
        mesh.vertices.len()
    );
    assert!((lam - exact).abs() / exact < 0.01, "λ₁ = {lam}");
    // the eigenfunction peaks at the centre
    let imax = (0..sol.u.len())
        .max_by(|&a, &b| sol.u[a].total_cmp(&sol.u[b]))
        .unwrap();
    assert!(mesh.vertices[imax].length() < 0.1);
}
