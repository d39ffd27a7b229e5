//! Print the thesis-digest figures the crate reproduces: `cargo run -p metrocell-physics --example seed_figures`.

use metrocell_physics::instrument::edlen::*;
use metrocell_physics::instrument::tracker_warmup::{settling_time, warmup_drift};

fn main() {
    let (p, t, h) = (99_000.0, 20.0, 50.0);
    println!(
        "shop-floor Edlén n(99 kPa, 20 °C, 50 %RH) = {:.14}",
        shop_floor_index(p, t, h)
    );
    println!(
        "Birch & Downs (632.99 nm)                 = {:.12}",
        birch_downs_index(632.99e-9, p, t, h)
    );
    println!(
        "Bönsch & Potulski (632.99 nm, 400 ppm)    = {:.12}",
        boensch_potulski_index(632.99e-9, p, t, h, 400e-6)
    );
    println!(
        "dn/dt = {:.4e} /K, dn/dp = {:.4e} /kPa",
        shop_floor_index_dt(p, t, h),
        shop_floor_index_dp(p, t, h) * 1e3
    );
    let sig = StationUncertainty {
        temperature: 0.15,
        pressure: 50.0,
        humidity: 2.5,
    };
    println!(
        "weather-station MC 2σ = {:.4} µm/m",
        weather_station_scale_error_2sigma(p, t, h, sig, 10_000, 1) * 1e6
    );
    let n = shop_floor_index(p, t, h);
    println!(
        "heated 0.5 m of 2 m by 17 K: {:.3} µm",
        segmented_path_range_error(&[(1.5, n), (0.5, shop_floor_index(p, 37.0, h))], n) * 1e6
    );
    for (g, l) in [(0.1, 10.0), (1.0, 10.0)] {
        let d = l * (shop_floor_index(p, t + g * l / 2.0, h) / n - 1.0);
        println!("gradient {g} K/m over {l} m: {:.2} µm", d * 1e6);
    }
    println!(
        "95 % settling: τ 30 min → {:.2} min, τ 90 min → {:.2} min",
        settling_time(1800.0, 0.95) / 60.0,
        settling_time(5400.0, 0.95) / 60.0
    );
    for (name, b, tau, ts) in [
        ("API", 0.019e-3, 30.0, [90.0, 1e9]),
        ("Leica", 0.075e-3, 90.0, [95.0, 270.0]),
    ] {
        for tm in ts {
            println!(
                "{name} drift at {tm} min: {:.2} µm",
                warmup_drift(0.0, b, tau * 60.0, tm * 60.0) * 1e6
            );
        }
    }
}
