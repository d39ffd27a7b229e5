//! The program the machine runs during a verification: for each point in visiting order, the
//! approach, the point, a dwell while the tracker measures. Every move is a G1 at one feed, so
//! the time the machine reaches each point follows the thesis's T_v = L_T/F + T_s·(n − 1) when
//! the controller's position is not streamed (crates/tracker `time_alignment`).

use crate::visiting_order::approach_start;

/// How the controller spells a dwell of s seconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DwellWord {
    /// `G4 P<s>`: LinuxCNC, Haas, Mach3/4 (P in seconds).
    P,
    /// `G4 X<s>`: Fanuc, Siemens-ISO mode (X in seconds; Fanuc's P would be milliseconds).
    X,
    /// `G4 S<s>`: Marlin, Klipper (S in seconds; their P is milliseconds).
    S,
}

/// One stop of the program: the machine stands at `point` (m) for the dwell.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop {
    /// The target name the tracker's software should give this measurement (p0, p1, …, nest).
    pub name: String,
    pub point: [f64; 3],
}

/// The program's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramSettings {
    /// m/s
    pub feed: f64,
    /// s
    pub dwell: f64,
    /// m, 0 = go straight to each point
    pub approach: f64,
    pub dwell_word: DwellWord,
    /// Revisit the first point (named `nest`) after every this many points, so the tracker
    /// node can follow the tracker's warm-up on it; 0 = never.
    pub nest_every: usize,
}

/// The stops in the order the machine makes them: the points, with the nest revisited.
pub fn stops(points_in_order: &[[f64; 3]], nest_every: usize) -> Vec<Stop> {
    let mut out = Vec::new();
    for (k, p) in points_in_order.iter().enumerate() {
        if nest_every > 0 && k > 0 && k % nest_every == 0 {
            out.push(Stop {
                name: "nest".into(),
                point: points_in_order[0],
            });
        }
        out.push(Stop {
            name: format!("p{k}"),
            point: *p,
        });
    }
    if nest_every > 0 && points_in_order.len() > 1 {
        out.push(Stop {
            name: "nest".into(),
            point: points_in_order[0],
        });
    }
    out
}

/// When the machine reaches each stop (s after it leaves `home`), moving at the feed along the
/// program's path (the approach legs included) and dwelling at each earlier stop: the thesis's
/// T_v = L_T/F + T_s·(n − 1) (P5 eq. 4), which the tracker node applies when the controller's
/// position is not streamed.
pub fn arrival_times(stops: &[Stop], home: [f64; 3], settings: &ProgramSettings) -> Vec<f64> {
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut at = home;
    let mut path = 0.0;
    stops
        .iter()
        .enumerate()
        .map(|(k, s)| {
            if settings.approach > 0.0 {
                let a = approach_start(s.point, settings.approach);
                path += dist(at, a);
                at = a;
            }
            path += dist(at, s.point);
            at = s.point;
            metrocell_laser_tracker::time_alignment::program_point_time(
                path,
                settings.feed,
                settings.dwell,
                k as u32 + 1,
            )
        })
        .collect()
}

fn mm(v: f64) -> String {
    format!("{:.4}", v * 1e3)
}

/// The G-code of the verification (mm, absolute), with a comment naming each stop.
pub fn gcode(stops: &[Stop], settings: &ProgramSettings, title: &str) -> String {
    let mut g = header(stops, settings, title);
    g += &stop_moves(stops, settings);
    g += "M30\n";
    g
}

/// The program of a verification with the reflector at several offsets on the spindle (m, from
/// its gauge point): the stops once per reflector, each pass after a program stop (M0) at which
/// the operator moves the reflector and publishes its offset. The commanded positions are the
/// same in every pass (no tool length compensation): the reflector's offset moves the target,
/// and the model sees the angular errors through the longer arms.
pub fn multi_reflector_gcode(
    stops: &[Stop],
    settings: &ProgramSettings,
    title: &str,
    reflectors: &[[f64; 3]],
) -> String {
    let mut g = header(stops, settings, title);
    let n = reflectors.len();
    g += &format!("; {n} passes, one per reflector offset; every pass makes the same stops\n");
    for (k, r) in reflectors.iter().enumerate() {
        let at = format!("({}, {}, {}) mm", mm(r[0]), mm(r[1]), mm(r[2]));
        g += &format!(
            "; pass {} of {n}: the reflector at {at} from the spindle's gauge point\n",
            k + 1
        );
        g += &format!(
            "M0 ; stop: put the reflector at {at}; publish it: metrocell topic pub --once /machine/tool_offset geometry_msgs/msg/PointStamped '{{header: {{frame_id: machine}}, point: {{x: {}, y: {}, z: {}}}}}'; then cycle start\n",
            r[0], r[1], r[2]
        );
        g += &stop_moves(stops, settings);
    }
    g += "M30\n";
    g
}

fn header(stops: &[Stop], settings: &ProgramSettings, title: &str) -> String {
    let mut g = String::new();
    g += &format!("; {title}\n");
    g += &format!(
        "; {} stops; every move G1 at F{:.0} mm/min; dwell {} s at each stop{}\n",
        stops.len(),
        settings.feed * 60e3,
        settings.dwell,
        if settings.approach > 0.0 {
            format!(
                "; each stop approached in + on every axis over the last {} mm (backlash taken up the same way everywhere)",
                mm(settings.approach)
            )
        } else {
            String::new()
        }
    );
    g += "; the tracker measures the target during each dwell; name its measurement as the comment says\n";
    g += "G21 G90 G17 G94\n";
    g += &format!("G1 F{:.1}\n", settings.feed * 60e3);
    g
}

/// Each stop: the approach, the point (its name in a comment), the dwell.
fn stop_moves(stops: &[Stop], settings: &ProgramSettings) -> String {
    let mut g = String::new();
    let dwell = match settings.dwell_word {
        DwellWord::P => format!("G4 P{}", settings.dwell),
        DwellWord::X => format!("G4 X{}", settings.dwell),
        DwellWord::S => format!("G4 S{}", settings.dwell),
    };
    for s in stops {
        let p = s.point;
        if settings.approach > 0.0 {
            let a = approach_start(p, settings.approach);
            g += &format!("G1 X{} Y{} Z{}\n", mm(a[0]), mm(a[1]), mm(a[2]));
        }
        g += &format!(
            "G1 X{} Y{} Z{} ; {}\n",
            mm(p[0]),
            mm(p[1]),
            mm(p[2]),
            s.name
        );
        g += &format!("{dwell}\n");
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed 001 part 2, fixture 16: 200 mm of path at 1000 mm/min to the third point, 5 s
    /// stops: 12 s + 10 s = 22 s.
    #[test]
    fn the_third_point_is_reached_at_22_s() {
        let pts = [[0.05, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]];
        let settings = ProgramSettings {
            feed: 1.0 / 60.0,
            dwell: 5.0,
            approach: 0.0,
            dwell_word: DwellWord::P,
            nest_every: 0,
        };
        let t = arrival_times(&stops(&pts, 0), [0.0; 3], &settings);
        assert!((t[2] - 22.0).abs() < 1e-9, "{t:?}");
        assert!((t[0] - 3.0).abs() < 1e-9);
    }

    #[test]
    fn each_stop_is_approached_in_plus_and_dwelt_at() {
        let pts = [[0.1, 0.2, 0.3], [0.0, 0.2, 0.3], [0.1, 0.1, 0.3]];
        let s = stops(&pts, 2);
        let names: Vec<&str> = s.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["p0", "p1", "nest", "p2", "nest"]);
        let settings = ProgramSettings {
            feed: 0.05,
            dwell: 5.0,
            approach: 0.002,
            dwell_word: DwellWord::X,
            nest_every: 2,
        };
        let g = gcode(&s, &settings, "test");
        let lines: Vec<&str> = g.lines().collect();
        assert!(lines.contains(&"G1 F3000.0"));
        let i = lines.iter().position(|l| l.ends_with("; p1")).unwrap();
        assert_eq!(lines[i - 1], "G1 X-2.0000 Y198.0000 Z298.0000");
        assert_eq!(lines[i], "G1 X0.0000 Y200.0000 Z300.0000 ; p1");
        assert_eq!(lines[i + 1], "G4 X5");
        assert_eq!(g.matches("G4 X5").count(), 5);
        assert_eq!(*lines.last().unwrap(), "M30");
    }

    #[test]
    fn a_pass_per_reflector_each_after_a_program_stop() {
        let pts = [[0.1, 0.2, 0.3], [0.0, 0.2, 0.3]];
        let s = stops(&pts, 0);
        let settings = ProgramSettings {
            feed: 0.05,
            dwell: 4.0,
            approach: 0.0,
            dwell_word: DwellWord::P,
            nest_every: 0,
        };
        let g = multi_reflector_gcode(&s, &settings, "t", &[[0.0, 0.0, -0.1], [0.15, 0.0, -0.1]]);
        assert_eq!(g.matches("\nM0 ").count(), 2, "{g}");
        assert_eq!(g.matches("G4 P4").count(), 4);
        assert_eq!(g.matches("; p1\n").count(), 2);
        let second = g
            .find("pass 2 of 2: the reflector at (150.0000, 0.0000, -100.0000) mm")
            .unwrap();
        assert!(
            g[second..].contains("point: {x: 0.15, y: 0, z: -0.1}"),
            "{g}"
        );
        assert!(g.ends_with("M30\n"));
        // one reflector's passes are the plain program's stops
        assert_eq!(gcode(&s, &settings, "t").matches("G4 P4").count(), 2);
    }
}
