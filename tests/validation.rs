//! Validation against published references at quick sizes; `coil validate` runs the full set
//! and reports each error against its tolerance.

use coil::scene::ViscosityOperator;
use coil::validation::poiseuille::{cross_steady_velocity, startup_velocity, Channel, CrossLaw};
use coil::validation::startup_poiseuille;

#[test]
fn the_startup_series_starts_at_rest_and_ends_at_the_parabola() {
    let ch = Channel::morris(30, ViscosityOperator::Stress);
    let peak = ch.newtonian_peak();
    assert!((peak - 2.5e-5).abs() < 1e-18);
    for k in 0..=20 {
        let y = k as f64 * ch.gap_m / 20.0;
        assert!(startup_velocity(&ch, y, 0.0).abs() < 2e-3 * peak, "t = 0, y = {y}: {}", startup_velocity(&ch, y, 0.0));
        let steady = ch.force_m_s2 / (2.0 * ch.nu0_m2_s) * y * (ch.gap_m - y);
        assert!((startup_velocity(&ch, y, 50.0) - steady).abs() < 1e-12 * peak);
    }
}

#[test]
fn the_cross_reference_is_the_parabola_when_the_fluid_is_newtonian_and_faster_when_it_thins() {
    let ch = Channel::morris(30, ViscosityOperator::Stress);
    let ys: Vec<f64> = (0..=20).map(|k| k as f64 * ch.gap_m / 20.0).collect();
    let newtonian = CrossLaw { nu_inf_m2_s: ch.nu0_m2_s, k_s: 1.0, n: 1.0 };
    for (&y, u) in ys.iter().zip(cross_steady_velocity(&ch, &newtonian, &ys)) {
        let steady = ch.force_m_s2 / (2.0 * ch.nu0_m2_s) * y * (ch.gap_m - y);
        // The midpoint rule on 4000 intervals: error O(1/4000^2) of the peak.
        assert!((u - steady).abs() < 1e-6 * ch.newtonian_peak(), "y = {y}: {u} against {steady}");
    }
    let thinning = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s: 10.0, n: 1.0 };
    let centre = cross_steady_velocity(&ch, &thinning, &[0.5 * ch.gap_m])[0];
    // Between the Newtonian peaks of nu0 and nu_inf.
    assert!(centre > ch.newtonian_peak() && centre < 4.0 * ch.newtonian_peak(), "{centre}");
}

/// Zero-velocity wall particles put the no-slip plane about half a spacing outside the wall
/// (measured: see README "Validation"), an error of order spacing / gap: so the error must
/// roughly halve when the resolution doubles, and stay below what was measured with margin.
#[test]
fn startup_poiseuille_converges_with_resolution_laplacian() {
    let coarse = startup_poiseuille(10, ViscosityOperator::Laplacian, None).expect("stable");
    let fine = startup_poiseuille(20, ViscosityOperator::Laplacian, None).expect("stable");
    eprintln!("Laplacian operator: {:.4} at 10 across, {:.4} at 20 across", coarse.error, fine.error);
    assert!(fine.error < 0.7 * coarse.error, "{} then {}", coarse.error, fine.error);
    assert!(fine.error < 0.16, "{}", fine.error);
}
