//! Leica GSI (Geo Serial Interface) measurement blocks from a total station, and the point in
//! the instrument frame they give.
//!
//! # The format followed
//! From the Leica TPS1100 Professional Series User Manual 2.2.1en, chapter "Data format"
//! (pp. 108–116: word layout, GSI-8/GSI-16, the units table of position 6) and the Leica
//! Captivate manual's "Output format – GSI" (word 51 = "PPM total/mm"); word indices as the
//! TC1100 GSI tables list them:
//!
//! * A block is one line of words separated by one blank. GSI-8 words are 15 characters plus
//!   the blank, GSI-16 words 23 plus the blank; a GSI-16 block starts with `*`.
//! * Word positions (1-based): 1–2 word index (WI); 3–6 additional information — in word 11 the
//!   block number, otherwise 3 reserved (`.`), 4 automatic index information, 5 input mode,
//!   6 **units**; 7 sign (`+`/`-`); 8–15 (GSI-8) or 8–23 (GSI-16) data, no decimal point.
//! * Units digit (position 6) and the places after the (implied) decimal point:
//!   `0` m, 3 (last digit 1 mm); `1` ft, 3; `2` 400 gon, 5; `3` 360° decimal, 5;
//!   `4` 360° sexagesimal DDD.MMSSS, 5 (minutes 2 digits, seconds 3 digits = SS.S);
//!   `5` 6400 mil, 4; `6` m, 4 (1/10 mm); `7` ft, 4 (1/10000 ft); `8` m, 5 (1/100 mm).
//!   Feet are international feet (0.3048 m).
//! * Words read here: 11 point id (alphanumeric, leading zeros are padding), 21 Hz (horizontal
//!   circle reading), 22 V (vertical circle, a zenith angle), 31 slope distance, 32 horizontal
//!   distance, 33 height difference, 51 ppm / prism constant (`+0000+034`: the sign and ppm
//!   digits, then the sign and the mm of the prism addition constant; in GSI-16 the same split
//!   at the last sign, a layout this module could not confirm from a GSI-16 sample). The slope
//!   distance is taken as the instrument sends it, its ppm and prism constant already applied;
//!   word 51 is kept for the record, not applied again. Other word indices (codes 41–49,
//!   remarks 71–79, coordinates 81–88, …) are accepted and ignored.
//!
//! A block with none of 21, 22, 31 (a code or information block) is not a measurement
//! (`Ok(None)`); a block with some but not all three is refused, naming the missing word.
//!
//! # The instrument frame (one convention)
//! Hz is measured **clockwise seen from above** (surveying), V is a **zenith angle** (0 up,
//! 100 gon horizontal in face I). The frame produced is right-handed with z up (the
//! compensator's vertical): **x toward Hz = 0, y toward Hz = 300 gon (270°, i.e. −90°)**, z
//! toward V = 0. In the spherical convention of `metrocell_msgs/TrackerMeasurement`
//! (azimuth from +x toward +y, elevation above the xy plane):
//! `azimuth = −Hz` (wrapped to (−π, π]), `elevation = π/2 − V`, `range` = slope distance.
//! Face II readings (V > 200 gon) are mapped to face I first: V_I = 400 gon − V_II,
//! Hz_I = Hz_II − 200 gon.
//!
//! The covariance is first-order propagation of independent σ_Hz = σ_V = the angle σ and
//! σ_SD = a + b·SD (a in m, b in ppm), as maker specifications state them (ISO 17123-3/-4).

use metrocell_compensation::spherical::{from_spherical, point_covariance};
use nalgebra::{Matrix3, Vector3};
use std::f64::consts::{PI, TAU};

/// International foot, m.
const FOOT: f64 = 0.3048;

/// Word length of the block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GsiFormat {
    /// 8 data characters per word
    Gsi8,
    /// 16 data characters per word; the block starts with `*`
    Gsi16,
}

impl GsiFormat {
    fn data_len(self) -> usize {
        match self {
            GsiFormat::Gsi8 => 8,
            GsiFormat::Gsi16 => 16,
        }
    }
}

/// What is wrong with a block.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GsiError {
    /// A word that cannot be read: its 1-based number in the block, the 1-based column of its
    /// first character in the line, its text.
    #[error("GSI word {word} at column {column} ('{text}'): {reason}")]
    Word {
        word: usize,
        column: usize,
        text: String,
        reason: String,
    },
    #[error("GSI block has {present} but no word {index} ({name})")]
    Missing {
        index: u8,
        name: &'static str,
        present: String,
    },
    #[error("GSI block: {0}")]
    Block(String),
}

/// One measurement block, values in SI (angles rad, distances m) as the instrument sent them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GsiBlock {
    /// word 11, leading zeros removed
    pub point_id: Option<String>,
    /// word 21, rad, clockwise from the circle's zero, normalised to [0, 2π)
    pub hz: Option<f64>,
    /// word 22, rad, zenith angle as read (face II > π)
    pub v: Option<f64>,
    /// word 31, m
    pub slope_distance: Option<f64>,
    /// word 32, m
    pub horizontal_distance: Option<f64>,
    /// word 33, m (signed)
    pub height_difference: Option<f64>,
    /// word 51: (ppm, prism addition constant in m), as applied by the instrument
    pub ppm_and_prism_constant: Option<(f64, f64)>,
}

/// One word split into its fields.
#[derive(Debug, Clone, PartialEq)]
struct Word<'a> {
    index: u8,
    /// position 6
    unit: u8,
    negative: bool,
    data: &'a str,
}

/// Parse one GSI line (without its terminator). `Ok(None)` for blank lines and blocks that hold
/// no measurement (no word 21, 22 or 31).
pub fn parse_gsi_line(line: &str) -> Result<Option<GsiBlock>, GsiError> {
    let trimmed = line.trim_end_matches(['\r', '\n']);
    if trimmed.trim().is_empty() {
        return Ok(None);
    }
    let (format, body_start) = match trimmed.strip_prefix('*') {
        Some(_) => (GsiFormat::Gsi16, 1),
        None => (GsiFormat::Gsi8, 0),
    };
    let mut block = GsiBlock::default();
    let mut seen: Vec<u8> = Vec::new();
    let mut number = 0;
    let mut offset = body_start;
    for token in trimmed[body_start..].split(' ') {
        let column = offset + 1;
        offset += token.len() + 1;
        if token.is_empty() {
            continue;
        }
        number += 1;
        let bad = |reason: String| GsiError::Word {
            word: number,
            column,
            text: token.chars().take(40).collect(),
            reason,
        };
        let word = split_word(token, format).map_err(bad)?;
        if seen.contains(&word.index) {
            return Err(bad(format!(
                "word index {} appears twice in the block",
                word.index
            )));
        }
        seen.push(word.index);
        read_word(&mut block, &word).map_err(bad)?;
    }
    let measured = [
        block.hz.is_some(),
        block.v.is_some(),
        block.slope_distance.is_some(),
    ];
    if measured.iter().all(|m| !m) {
        return Ok(None);
    }
    let present = seen
        .iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    for (have, index, name) in [
        (measured[0], 21, "Hz"),
        (measured[1], 22, "V"),
        (measured[2], 31, "slope distance"),
    ] {
        if !have {
            return Err(GsiError::Missing {
                index,
                name,
                present: format!("words {present}"),
            });
        }
    }
    Ok(Some(block))
}

/// WI, info, sign, data of one word; its length must be that of the block's format.
fn split_word(token: &str, format: GsiFormat) -> Result<Word<'_>, String> {
    if !token.is_ascii() {
        return Err("not ASCII".into());
    }
    let expected = 7 + format.data_len();
    if token.len() != expected {
        let (name, other) = match format {
            GsiFormat::Gsi8 => ("GSI-8 (no leading '*')", "a GSI-16 block starts with '*'"),
            GsiFormat::Gsi16 => ("GSI-16 (leading '*')", "GSI-8 blocks have no '*'"),
        };
        return Err(format!(
            "{} characters; a {name} word has {expected}; {other}",
            token.len()
        ));
    }
    let index = token[..2]
        .parse::<u8>()
        .ok()
        .filter(|_| token[..2].bytes().all(|b| b.is_ascii_digit()))
        .ok_or_else(|| format!("word index '{}' is not two digits", &token[..2]))?;
    let negative = match token.as_bytes()[6] {
        b'+' => false,
        b'-' => true,
        c => {
            return Err(format!(
                "position 7 is '{}', expected the sign + or -",
                c as char
            ))
        }
    };
    Ok(Word {
        index,
        unit: token.as_bytes()[5],
        negative,
        data: &token[7..],
    })
}

/// Store a word's value in the block (unknown word indices are ignored).
fn read_word(block: &mut GsiBlock, w: &Word) -> Result<(), String> {
    match w.index {
        11 => {
            let id = w.data.trim_start_matches('0');
            block.point_id = Some(if id.is_empty() {
                "0".to_string()
            } else {
                id.to_string()
            });
        }
        21 => block.hz = Some(angle(w)?.rem_euclid(TAU)),
        22 => block.v = Some(angle(w)?),
        31 => block.slope_distance = Some(distance(w)?),
        32 => block.horizontal_distance = Some(distance(w)?),
        33 => block.height_difference = Some(distance(w)?),
        51 => block.ppm_and_prism_constant = Some(ppm_and_constant(w)?),
        _ => {}
    }
    Ok(())
}

fn digits(w: &Word) -> Result<u64, String> {
    if !w.data.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("data '{}' is not all digits", w.data));
    }
    w.data
        .parse::<u64>()
        .map_err(|e| format!("data '{}': {e}", w.data))
}

fn signed(w: &Word, magnitude: f64) -> f64 {
    if w.negative {
        -magnitude
    } else {
        magnitude
    }
}

/// An angle word (units 2, 3, 4, 5) in rad.
fn angle(w: &Word) -> Result<f64, String> {
    let n = digits(w)?;
    let rad = match w.unit {
        b'2' => n as f64 * 1e-5 * PI / 200.0,
        b'3' => (n as f64 * 1e-5).to_radians(),
        b'4' => {
            let (deg, min, tenth_sec) = (n / 100_000, (n / 1000) % 100, n % 1000);
            if min >= 60 || tenth_sec >= 600 {
                return Err(format!("sexagesimal DDD.MMSSS '{}' has {min} minutes, {:.1} seconds", w.data, tenth_sec as f64 / 10.0));
            }
            (deg as f64 + min as f64 / 60.0 + tenth_sec as f64 / 36_000.0).to_radians()
        }
        b'5' => n as f64 * 1e-4 * TAU / 6400.0,
        u => return Err(format!("unit digit '{}' (position 6) is not an angle unit: 2 = 400 gon, 3 = 360° decimal, 4 = 360° sexagesimal, 5 = 6400 mil", u as char)),
    };
    Ok(signed(w, rad))
}

/// A distance word (units 0, 1, 6, 7, 8) in m.
fn distance(w: &Word) -> Result<f64, String> {
    let n = digits(w)? as f64;
    let m = match w.unit {
        b'0' => n * 1e-3,
        b'1' => n * 1e-3 * FOOT,
        b'6' => n * 1e-4,
        b'7' => n * 1e-4 * FOOT,
        b'8' => n * 1e-5,
        u => return Err(format!("unit digit '{}' (position 6) is not a distance unit: 0 = m (1 mm), 1 = ft (1/1000), 6 = m (1/10 mm), 7 = ft (1/10000), 8 = m (1/100 mm)", u as char)),
    };
    Ok(signed(w, m))
}

/// Word 51: `<sign><ppm digits><sign><mm digits>` → (ppm, prism constant in m).
fn ppm_and_constant(w: &Word) -> Result<(f64, f64), String> {
    let split = w.data.rfind(['+', '-']).ok_or_else(|| {
        format!(
            "data '{}' has no sign before the prism constant (expected e.g. 0000+034)",
            w.data
        )
    })?;
    let (ppm, mm) = (&w.data[..split], &w.data[split + 1..]);
    let number = |s: &str| {
        s.parse::<u32>()
            .ok()
            .filter(|_| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
    };
    let (Some(ppm), Some(mm)) = (number(ppm), number(mm)) else {
        return Err(format!(
            "data '{}' is not <ppm digits><sign><mm digits>",
            w.data
        ));
    };
    let mm_sign = if w.data.as_bytes()[split] == b'-' {
        -1.0
    } else {
        1.0
    };
    Ok((signed(w, ppm as f64), mm_sign * mm as f64 * 1e-3))
}

/// Standard uncertainties of one total-station observation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TotalStationNoise {
    /// σ of Hz and of V, rad
    pub angle: f64,
    /// a of σ_SD = a + b·SD, m
    pub distance_constant: f64,
    /// b of σ_SD = a + b·SD, ppm (1e-6 m/m)
    pub distance_ppm: f64,
}

/// The point a block gives, in the instrument frame of the module doc.
#[derive(Debug, Clone, PartialEq)]
pub struct InstrumentPoint {
    /// m
    pub point: Vector3<f64>,
    /// m², row i / column j = x, y, z
    pub covariance: Matrix3<f64>,
    /// m, the slope distance
    pub range: f64,
    /// rad, −Hz_I wrapped to (−π, π]
    pub azimuth: f64,
    /// rad, π/2 − V_I
    pub elevation: f64,
    /// the reading was taken in face II (and mapped to face I)
    pub face_two: bool,
}

/// Face-I (Hz, V) of a reading: V in (π, 2π) is face II.
pub fn face_one(hz: f64, v: f64) -> (f64, f64, bool) {
    if v > PI {
        ((hz - PI).rem_euclid(TAU), TAU - v, true)
    } else {
        (hz.rem_euclid(TAU), v, false)
    }
}

/// Hz, V (rad, as read, either face) and slope distance (m) → point and covariance.
pub fn to_instrument_frame(
    hz: f64,
    v: f64,
    slope_distance: f64,
    noise: &TotalStationNoise,
) -> Result<InstrumentPoint, GsiError> {
    if !(hz.is_finite() && v.is_finite() && slope_distance.is_finite()) {
        return Err(GsiError::Block(format!(
            "Hz {hz}, V {v}, SD {slope_distance} are not all finite"
        )));
    }
    if !(0.0..TAU).contains(&v) {
        return Err(GsiError::Block(format!(
            "V = {:.5} gon is outside 0..400 gon",
            v * 200.0 / PI
        )));
    }
    if slope_distance <= 0.0 {
        return Err(GsiError::Block(format!(
            "slope distance {slope_distance} m is not positive"
        )));
    }
    let (hz1, v1, face_two) = face_one(hz, v);
    let mut azimuth = -hz1;
    if azimuth <= -PI {
        azimuth += TAU;
    }
    let elevation = PI / 2.0 - v1;
    let sigma_range = noise.distance_constant + noise.distance_ppm * 1e-6 * slope_distance;
    Ok(InstrumentPoint {
        point: from_spherical(slope_distance, azimuth, elevation),
        covariance: point_covariance(
            slope_distance,
            azimuth,
            elevation,
            sigma_range,
            noise.angle,
            noise.angle,
        ),
        range: slope_distance,
        azimuth,
        elevation,
        face_two,
    })
}

/// A measurement block → point id (empty when the block has none) and point.
pub fn block_to_point(
    block: &GsiBlock,
    noise: &TotalStationNoise,
) -> Result<(String, InstrumentPoint), GsiError> {
    let (Some(hz), Some(v), Some(sd)) = (block.hz, block.v, block.slope_distance) else {
        return Err(GsiError::Block(
            "a measurement needs words 21 (Hz), 22 (V) and 31 (slope distance)".into(),
        ));
    };
    Ok((
        block.point_id.clone().unwrap_or_default(),
        to_instrument_frame(hz, v, sd, noise)?,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_noise::normal;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    const GON: f64 = PI / 200.0;

    fn no_noise() -> TotalStationNoise {
        TotalStationNoise {
            angle: 0.0,
            distance_constant: 0.0,
            distance_ppm: 0.0,
        }
    }

    #[test]
    fn gsi8_block_in_gon_and_mm() {
        // written from the TPS1100 layout: point 7, Hz 123.45670 gon, V 95.00000 gon, SD 12.345 m,
        // 51: 0 ppm, +34 mm
        let b = parse_gsi_line(
            "110007+00000007 21.322+12345670 22.322+09500000 31..00+00012345 51..1.+0000+034 ",
        )
        .unwrap()
        .unwrap();
        assert_eq!(b.point_id.as_deref(), Some("7"));
        assert!((b.hz.unwrap() - 123.4567 * GON).abs() < 1e-15);
        assert!((b.v.unwrap() - 95.0 * GON).abs() < 1e-15);
        assert!((b.slope_distance.unwrap() - 12.345).abs() < 1e-15);
        assert_eq!(b.ppm_and_prism_constant, Some((0.0, 0.034)));
    }

    #[test]
    fn gsi16_block_with_every_unit_of_the_table() {
        let line = "*110012+00000000000PT_12 21.324+0000000012345120 22.323+0000000009012345 31..08+0000000000250000 32..06+0000000000024999 33..01+0000000000001000\r";
        let b = parse_gsi_line(line).unwrap().unwrap();
        assert_eq!(b.point_id.as_deref(), Some("PT_12"));
        // 123° 45' 12.0"
        assert!(
            (b.hz.unwrap() - (123.0 + 45.0 / 60.0 + 12.0 / 3600.0_f64).to_radians()).abs() < 1e-15
        );
        assert!((b.v.unwrap() - 90.12345_f64.to_radians()).abs() < 1e-15);
        assert!((b.slope_distance.unwrap() - 2.5).abs() < 1e-15); // 1/100 mm
        assert!((b.horizontal_distance.unwrap() - 2.4999).abs() < 1e-15); // 1/10 mm
        assert!((b.height_difference.unwrap() - 1.0 * FOOT).abs() < 1e-15); // 1/1000 ft
                                                                            // 1600.0000 mil (6400 per turn) = 90°, and ft at 1/10000
        let b = parse_gsi_line(
            "*21..05+0000000016000000 22..05+0000000016000000 31..07+0000000000010000",
        )
        .unwrap()
        .unwrap();
        assert!(
            (b.hz.unwrap() - PI / 2.0).abs() < 1e-15 && (b.v.unwrap() - PI / 2.0).abs() < 1e-15
        );
        assert!((b.slope_distance.unwrap() - FOOT).abs() < 1e-15);
        assert_eq!(b.point_id, None);
    }

    #[test]
    fn negative_words_keep_their_sign() {
        // height difference −1.234 m; a Hz sent as −50 gon is the circle reading 350 gon
        let b = parse_gsi_line("*110001+0000000000000001 21.022-0000000005000000 22.022+0000000010000000 31..00+0000000000002000 33..00-0000000000001234").unwrap().unwrap();
        assert!((b.height_difference.unwrap() + 1.234).abs() < 1e-15);
        assert!((b.hz.unwrap() - 350.0 * GON).abs() < 1e-12);
        let b = parse_gsi_line(
            "110001+00000001 21.022+00000000 22.022+10000000 31..00+00002000 51....-0012-002",
        )
        .unwrap()
        .unwrap();
        assert_eq!(b.ppm_and_prism_constant, Some((-12.0, -0.002)));
    }

    #[test]
    fn code_blocks_are_not_measurements_and_blank_lines_are_nothing() {
        assert_eq!(
            parse_gsi_line("410001+00130027 42....+00001810 43....+00000010"),
            Ok(None)
        );
        assert_eq!(parse_gsi_line("  \r"), Ok(None));
    }

    #[test]
    fn malformed_words_are_named_with_their_position() {
        // the 3rd word's unit digit is '9'
        let e = parse_gsi_line("110001+00000001 21.022+10000000 22.029+10000000 31..00+00002000")
            .unwrap_err();
        assert_eq!(
            e,
            GsiError::Word {
                word: 3,
                column: 33,
                text: "22.029+10000000".into(),
                reason: e.reason()
            }
        );
        assert!(
            e.to_string()
                .starts_with("GSI word 3 at column 33 ('22.029+10000000'): unit digit '9'"),
            "{e}"
        );
        // a GSI-8 word in a GSI-16 block (word 2, after '*' and a 24-character word)
        let e = parse_gsi_line("*110001+0000000000000001 21.022+10000000")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("GSI word 2 at column 26")
                && e.contains("15 characters; a GSI-16 (leading '*') word has 23"),
            "{e}"
        );
        // letters in a distance, a missing sign, minutes ≥ 60
        assert!(parse_gsi_line("110001+00000001 21.022+10000000 22.022+10000000 31..00+0000x000").unwrap_err().to_string().contains("GSI word 4 at column 49 ('31..00+0000x000'): data '0000x000' is not all digits"));
        assert!(
            parse_gsi_line("110001+00000001 21.022*10000000 22.022+10000000 31..00+00002000")
                .unwrap_err()
                .to_string()
                .contains("GSI word 2 at column 17 ('21.022*10000000'): position 7 is '*'")
        );
        assert!(
            parse_gsi_line("21.024+12361000 22.022+10000000 31..00+00002000")
                .unwrap_err()
                .to_string()
                .contains("61 minutes")
        );
        assert!(parse_gsi_line("21.022+10000000 21.022+10000000")
            .unwrap_err()
            .to_string()
            .contains("GSI word 2 at column 17 ('21.022+10000000'): word index 21 appears twice"));
    }

    #[test]
    fn a_measurement_missing_a_word_is_refused_naming_it() {
        let e = parse_gsi_line("110001+00000001 21.022+10000000 22.022+10000000").unwrap_err();
        assert_eq!(
            e.to_string(),
            "GSI block has words 11, 21, 22 but no word 31 (slope distance)"
        );
    }

    impl GsiError {
        fn reason(&self) -> String {
            match self {
                GsiError::Word { reason, .. } => reason.clone(),
                _ => String::new(),
            }
        }
    }

    #[test]
    fn known_points_converted_by_hand() {
        // Hz 50 gon (45° clockwise from x), V 100 gon (horizontal), 10 m: x = y·(−1) = 10/√2, z = 0
        let p = to_instrument_frame(50.0 * GON, 100.0 * GON, 10.0, &no_noise()).unwrap();
        assert!(
            (p.point - Vector3::new(10.0 / 2f64.sqrt(), -10.0 / 2f64.sqrt(), 0.0)).norm() < 1e-14,
            "{:?}",
            p.point
        );
        assert!((p.azimuth + PI / 4.0).abs() < 1e-15 && p.elevation.abs() < 1e-15 && !p.face_two);
        // Hz 100 gon (90° clockwise = −y), V 50 gon (45° above the horizon), 2 m
        let p = to_instrument_frame(100.0 * GON, 50.0 * GON, 2.0, &no_noise()).unwrap();
        assert!(
            (p.point - Vector3::new(0.0, -2f64.sqrt(), 2f64.sqrt())).norm() < 1e-14,
            "{:?}",
            p.point
        );
        // Hz 300 gon is +y
        let p = to_instrument_frame(300.0 * GON, 100.0 * GON, 3.0, &no_noise()).unwrap();
        assert!((p.point - Vector3::new(0.0, 3.0, 0.0)).norm() < 1e-14);
        assert!((p.azimuth - PI / 2.0).abs() < 1e-15);
    }

    #[test]
    fn face_two_gives_the_face_one_point() {
        // face II of (Hz 100, V 50): Hz 300, V 350 gon — as a GSI-8 block
        let b = parse_gsi_line("110002+000000P2 21.322+30000000 22.322+35000000 31..00+00002000")
            .unwrap()
            .unwrap();
        let (id, p) = block_to_point(&b, &no_noise()).unwrap();
        assert_eq!(id, "P2");
        assert!(p.face_two);
        assert!(
            (p.point - Vector3::new(0.0, -2f64.sqrt(), 2f64.sqrt())).norm() < 1e-12,
            "{:?}",
            p.point
        );
        // Hz 0 in face II is Hz 200 in face I: −x
        let p = to_instrument_frame(0.0, 300.0 * GON, 1.0, &no_noise()).unwrap();
        assert!(
            (p.point - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12
                && (p.azimuth - PI).abs() < 1e-12
        );
        assert!(to_instrument_frame(0.0, 400.0 * GON, 1.0, &no_noise()).is_err());
        assert!(to_instrument_frame(0.0, 100.0 * GON, 0.0, &no_noise()).is_err());
    }

    #[test]
    fn covariance_matches_a_monte_carlo_of_the_angle_and_distance_noise() {
        // 1″ angles, 1 mm + 2 ppm, at 40 m, 30 gon above the horizon, face II as read
        let noise = TotalStationNoise {
            angle: (1.0 / 3600.0_f64).to_radians(),
            distance_constant: 1e-3,
            distance_ppm: 2.0,
        };
        let (hz, v, sd) = (237.0 * GON, 330.0 * GON, 40.0);
        let analytic = to_instrument_frame(hz, v, sd, &noise).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(27);
        let n = 40_000;
        let sigma_sd = 1e-3 + 2e-6 * sd;
        let samples: Vec<Vector3<f64>> = (0..n)
            .map(|_| {
                let (h, z, d) = (
                    hz + noise.angle * normal(&mut rng),
                    v + noise.angle * normal(&mut rng),
                    sd + sigma_sd * normal(&mut rng),
                );
                to_instrument_frame(h, z, d, &no_noise()).unwrap().point
            })
            .collect();
        let mean = samples.iter().sum::<Vector3<f64>>() / n as f64;
        let cov = samples
            .iter()
            .map(|s| (s - mean) * (s - mean).transpose())
            .sum::<Matrix3<f64>>()
            / (n - 1) as f64;
        assert!((mean - analytic.point).norm() < 3.0 * sigma_sd / (n as f64).sqrt() + 1e-9);
        // compare in the whitened frame: Σ_a^(-1/2) Σ_mc Σ_a^(-1/2) ≈ I within sampling error (~√(2/n) ≈ 0.7 %)
        let w = analytic
            .covariance
            .cholesky()
            .unwrap()
            .l()
            .try_inverse()
            .unwrap();
        let white = w * cov * w.transpose();
        assert!((white - Matrix3::identity()).abs().max() < 0.03, "{white}");
    }
}
