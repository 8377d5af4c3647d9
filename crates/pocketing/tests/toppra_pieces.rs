//! The TOPP-RA comparison cuts a path at its corner stops: the pieces cover the path, have no
//! corner and no repeated point inside, and our schedule's times over them add up to the
//! time of the whole path (so comparing piece by piece compares the path).

use glam::DVec2;
use thinplan_pocketing::bench::toppra_pieces;
use thinplan_pocketing::timing::{time_path, MachineLimits};

#[test]
fn pieces_split_at_corners_and_add_up() {
    let lim = MachineLimits::typical_hsm();
    // a quarter circle, a repeated point, a 90° corner, a straight run, a shallow bend (< 30°)
    let mut p: Vec<DVec2> = (0..=40)
        .map(|i| 20.0 * DVec2::from_angle(std::f64::consts::FRAC_PI_2 * i as f64 / 40.0))
        .collect();
    let corner = *p.last().unwrap();
    p.push(corner);
    p.push(corner + DVec2::new(0.0, -30.0)); // turns 90° at `corner`
    p.push(corner + DVec2::new(-5.0, -60.0)); // 9.5°: no corner
    let pieces = toppra_pieces(&p, lim.corner_angle_deg);
    assert_eq!(pieces.len(), 2, "{pieces:?}");
    assert_eq!(pieces[0].len(), 41);
    assert_eq!(pieces[1].len(), 3);
    assert_eq!(pieces[0].last(), pieces[1].first());
    let cos_lim = lim.corner_angle_deg.to_radians().cos();
    for piece in &pieces {
        for w in piece.windows(2) {
            assert!(w[0].distance(w[1]) > 0.0, "repeated point kept");
        }
        for w in piece.windows(3) {
            let (a, b) = ((w[1] - w[0]).normalize(), (w[2] - w[1]).normalize());
            assert!(a.dot(b) >= cos_lim, "corner inside a piece");
        }
    }
    let whole = time_path(&p, 500.0, &lim).total_time;
    let sum: f64 = pieces
        .iter()
        .map(|q| time_path(q, 500.0, &lim).total_time)
        .sum();
    assert!((sum - whole).abs() <= 1e-9 * whole, "{sum} vs {whole}");
}
