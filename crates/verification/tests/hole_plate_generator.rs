//! The hole plate analysis on plates measured by a machine written here from the geometry
//! alone (not from the analysis's model): axes as direction vectors, a pitch error that is a
//! sine (no polynomial), straightness bows, a yaw of X that grows along it, the Y axis leaning
//! by the thesis's squareness (0.20448 mrad), pitch of X acting over the probe's height
//! (an Abbe error the two heights see differently), the plate clamped 0.3° askew at 21.3 °C,
//! and 0.5 µm of probing noise on each of the four points of every ring.

use metrocell_verification::hole_plate::{plate_components, ring_centre, PlateMeasurement};
use nalgebra::{Rotation2, Vector2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const XWY: f64 = 0.20448e-3;

/// Where the machine's probe really is when commanded to (x, y) at height z (m), relative to
/// where it is at (0, 0, z).
fn machine(x: f64, y: f64, z: f64) -> Vector2<f64> {
    let pitch = 4e-6 * (2.0 * std::f64::consts::PI * x / 0.35).sin() + 12e-6 * x / 0.4; // xPx
    let y_pos = -9e-6 * (y / 0.4).powi(2) + 6e-6 * y / 0.4; // yPy
    let x_bow = 5e-6 * (x / 0.4) * (x / 0.4 - 1.0); // xTy: straightness of X in Y
    let y_bow = -4e-6 * (y / 0.4) * (y / 0.4 - 1.0); // yTx
    let yaw = 15e-6 * x / 0.4; // xRz: the table turns as X moves
    let x_pitch = 20e-6 * (x / 0.4 - 0.5); // pitch of X: the tip at height z moves by z·pitch in x
                                           // the Y motion's direction, leaning so the angle to +X is 90° + xWy
    let y_dir = Vector2::new(-XWY.sin(), XWY.cos());
    let nominal = Vector2::new(x, 0.0) + y_dir * y;
    nominal + Vector2::new(pitch + y_bow - y * yaw + z * x_pitch, y_pos + x_bow)
}

fn measure(nominal: &[Vector2<f64>], z: f64, temperature: f64, seed: u64) -> PlateMeasurement {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.5e-6).unwrap();
    let clamp = Vector2::new(0.2, 0.25);
    let placed = Rotation2::new(0.3f64.to_radians());
    let offset = Vector2::new(0.412, 0.137);
    let ring = 0.0125;
    let measured = nominal
        .iter()
        .map(|n| {
            // where the ring is on the table (expanded about the clamp, turned, shifted)
            let at = offset + placed * (clamp + (n - clamp) * (1.0 + 24e-6 * (temperature - 20.0)));
            // the machine is commanded to each probe point; it reaches machine(command); the
            // probe triggers on the ring wall: the reported point is the command at contact,
            // i.e. the wall's point less the machine's error there
            let touches: Vec<Vector2<f64>> = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
                .iter()
                .map(|(a, b)| {
                    let wall = at + Vector2::new(*a, *b) * ring;
                    let err = machine(wall.x, wall.y, z) - wall;
                    wall - err + Vector2::new(noise.sample(&mut rng), noise.sample(&mut rng))
                })
                .collect();
            ring_centre(&touches).unwrap()
        })
        .collect();
    PlateMeasurement {
        nominal: nominal.to_vec(),
        measured,
        temperature,
    }
}

#[test]
fn six_components_recover_the_squareness_and_compensate_most_of_the_plane() {
    // the peripheral rings of a 9 × 9 plate at 50 mm pitch (32), the first the origin
    let mut nominal = vec![];
    for i in 0..9 {
        for j in 0..9 {
            if i == 0 || j == 0 || i == 8 || j == 8 {
                nominal.push(Vector2::new(0.03 + 0.05 * i as f64, 0.03 + 0.05 * j as f64));
            }
        }
    }
    let low = measure(&nominal, 0.05, 21.3, 1);
    let high = measure(&nominal, 0.25, 21.3, 2);
    let c = plate_components(&[low, high], Vector2::new(0.2, 0.25), 24e-6).unwrap();
    let (s, u) = c.squareness;
    println!(
        "xWy = {:.5} ± {:.5} mrad (machine's {:.5} mrad); mean deviation {:.2} µm before, {:.2} µm after: {:.2} % compensated; residual RMS {:.2} µm",
        s * 1e3, u * 1e3, XWY * 1e3, c.mean_before * 1e6, c.mean_after * 1e6, c.compensated_percent, c.residual_rms * 1e6
    );
    assert!((s - XWY).abs() < 3.0 * u, "xWy {s} vs {XWY} (σ {u})");
    assert!(u < 0.02e-3, "squareness to 0.02 mrad: {u}");
    assert!(
        (85.0..99.5).contains(&c.compensated_percent),
        "{}",
        c.compensated_percent
    );
}

/// Is the squareness's σ honest? Over 200 plates (new probing noise each) the error of xWy
/// against the machine's, in units of the σ stated each time.
#[test]
fn the_squareness_sigma_covers_the_machines_value_at_its_rate() {
    let mut nominal = vec![];
    for i in 0..9 {
        for j in 0..9 {
            if i == 0 || j == 0 || i == 8 || j == 8 {
                nominal.push(Vector2::new(0.03 + 0.05 * i as f64, 0.03 + 0.05 * j as f64));
            }
        }
    }
    let mut z = vec![];
    for seed in 0..200u64 {
        let low = measure(&nominal, 0.05, 21.3, 100 + 2 * seed);
        let high = measure(&nominal, 0.25, 21.3, 101 + 2 * seed);
        let c = plate_components(&[low, high], Vector2::new(0.2, 0.25), 24e-6).unwrap();
        z.push((c.squareness.0 - XWY) / c.squareness.1);
    }
    let within = |k: f64| z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64;
    let mean = z.iter().sum::<f64>() / z.len() as f64;
    println!(
        "xWy z-scores over 200 plates: mean {mean:.3}, within 1σ {:.3}, 2σ {:.3}, 3σ {:.3}",
        within(1.0),
        within(2.0),
        within(3.0)
    );
    assert!((0.6..0.8).contains(&within(1.0)), "{}", within(1.0));
    assert!(within(2.0) > 0.92, "{}", within(2.0));
}
