//! Small image filters shared by the renderer and the detectors.

/// The normalised kernel of [`gaussian_blur_f64`]: radius ⌈4σ⌉ (at least 1), 2r + 1 taps.
pub fn gaussian_kernel(sigma: f64) -> Vec<f64> {
    let r = (4.0 * sigma).ceil().max(1.0) as isize;
    let mut k: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// Separable Gaussian blur with standard deviation `sigma` pixels, kernel radius ⌈4σ⌉,
/// edges replicated. Symmetric kernel, so edges are not shifted.
pub fn gaussian_blur_f64(src: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let k = gaussian_kernel(sigma);
    let r = (k.len() / 2) as isize;
    let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
    let mut tmp = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = 0.0;
            for (t, kv) in k.iter().enumerate() {
                acc += kv * src[y * w + clamp(x as isize + t as isize - r, w)];
            }
            tmp[y * w + x] = acc;
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = 0.0;
            for (t, kv) in k.iter().enumerate() {
                acc += kv * tmp[clamp(y as isize + t as isize - r, h) * w + x];
            }
            out[y * w + x] = acc;
        }
    }
    out
}
