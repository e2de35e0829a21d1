//! The BDS error simulator: zone boundaries, statistics of the white noise and of the
//! Gauss–Markov bias against their closed forms, outages, seeds.

use bds_ins_dynamics::{BdsSimulator, RtkStatus, Zone, scenario};

fn route(epochs: usize, bias: f64, tau: f64, availability: f64) -> Vec<Zone> {
    vec![
        Zone::white("open", 10, RtkStatus::Fixed, 22, 0.03, 0.001),
        Zone {
            bias_sigma: bias,
            bias_tau: tau,
            availability,
            ..Zone::white("crane", epochs, RtkStatus::Single, 5, 0.5, 0.01)
        },
    ]
}

#[test]
fn epochs_follow_the_zones_and_seeds_reproduce_runs() {
    let sim = BdsSimulator::new(route(5, 0.0, 1.0, 1.0), 1.0, 4).unwrap();
    assert_eq!(sim.len(), 15);
    let epochs: Vec<_> = sim.collect();
    assert_eq!(epochs.len(), 15);
    assert_eq!(epochs.iter().map(|e| e.k).collect::<Vec<_>>(), (1..=15).collect::<Vec<_>>());
    assert!(epochs[..10].iter().all(|e| e.zone == 0 && e.fix.is_some_and(|f| f.rtk == RtkStatus::Fixed)));
    assert!(epochs[10..].iter().all(|e| e.zone == 1 && e.fix.is_some_and(|f| f.satellites == 5)));
    let again: Vec<_> = BdsSimulator::new(route(5, 0.0, 1.0, 1.0), 1.0, 4).unwrap().collect();
    assert_eq!(epochs, again);
    let other: Vec<_> = BdsSimulator::new(route(5, 0.0, 1.0, 1.0), 1.0, 5).unwrap().collect();
    assert_ne!(epochs, other);
}

#[test]
fn white_noise_and_the_gauss_markov_bias_have_their_closed_form_statistics() {
    let (n, sb, tau) = (200_000, 0.8, 5.0);
    let fixes: Vec<_> =
        BdsSimulator::new(route(n, sb, tau, 1.0), 1.0, 11).unwrap().skip(10).filter_map(|e| e.fix).collect();
    assert_eq!(fixes.len(), n);
    let var = |v: &mut dyn Iterator<Item = f64>| {
        let xs: Vec<f64> = v.collect();
        let m = xs.iter().sum::<f64>() / xs.len() as f64;
        xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / xs.len() as f64
    };
    // Total horizontal variance σ_w² + σ_b² (the bias is stationary from the zone's entry).
    let v = var(&mut fixes.iter().map(|f| f.error[0]));
    assert!((v / (0.25 + sb * sb) - 1.0).abs() < 0.05, "east variance {v}");
    let vb = var(&mut fixes.iter().map(|f| f.bias[1]));
    assert!((vb / (sb * sb) - 1.0).abs() < 0.05, "bias variance {vb}");
    let vh = var(&mut fixes.iter().map(|f| f.error[2]));
    assert!((vh / 1e-4 - 1.0).abs() < 0.02, "heading variance {vh}");
    // Autocorrelation of the bias at lag τ: e^{−1}.
    let lag = tau as usize;
    let b: Vec<f64> = fixes.iter().map(|f| f.bias[0]).collect();
    let c0: f64 = b.iter().map(|x| x * x).sum::<f64>();
    let cl: f64 = b.windows(lag + 1).map(|w| w[0] * w[lag]).sum::<f64>();
    let rho = cl / c0;
    assert!((rho - (-1f64).exp()).abs() < 0.03, "ρ(τ) = {rho}");
}

#[test]
fn outages_occur_at_the_zones_rate() {
    let n = 20_000;
    let epochs: Vec<_> = BdsSimulator::new(route(n, 0.0, 1.0, 0.3), 1.0, 2).unwrap().skip(10).collect();
    let fixes = epochs.iter().filter(|e| e.fix.is_some()).count();
    assert!((fixes as f64 / n as f64 - 0.3).abs() < 0.02, "{fixes}");
    let none: Vec<_> = BdsSimulator::new(route(50, 0.0, 1.0, 0.0), 1.0, 2).unwrap().skip(10).collect();
    assert!(none.iter().all(|e| e.fix.is_none()));
}

#[test]
fn the_field_route_has_the_notes_working_states() {
    let epochs: Vec<_> = BdsSimulator::new(scenario::field_zones(0.2), 1.0, 1).unwrap().collect();
    assert_eq!(epochs.len(), 600);
    let at = |k: usize| epochs[k - 1].fix.map(|f| (f.rtk.code(), f.satellites));
    assert_eq!(at(300), Some((3, 22)));
    assert_eq!(at(301), Some((1, 5)));
    assert_eq!(at(421), Some((4, 10)));
}
