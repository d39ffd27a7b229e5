//! Compensating a whole program.
//!
//! Modal state starts as most controllers power up: G21 (mm), G90 (absolute), G17, no motion
//! mode, and the tool at [`CompensationOptions::start`]. Each motion line's programmed end point
//! (and, for G1 and arcs, points along the way) is replaced by the commanded point that makes
//! the machine reach it ([`crate::inverse`]). Straight G1 moves are split where the field bends
//! the compensated path by more than the chord tolerance; G2/G3 arcs become G1 chords. G0 end
//! points are compensated but rapid moves are not split (their path is not controlled).
//! The approach direction of each axis (for backlash) is the sign of its last non-zero motion.
//!
//! Lines are passed through byte for byte when compensation does not change them, when they are
//! malformed (reported with their line number), and when they use G codes whose effect on
//! coordinates metrocell does not model (G28, G30, G53, G92, G10, G38.x, cutter and tool-length
//! compensation, polar or absolute-arc modes; reported as warnings).

use nalgebra::Vector3;

use crate::arc::{arc_points, ArcCentre, ArcPlane};
use crate::block::{parse_block, Block};
use crate::error_field::ErrorField;
use crate::inverse::{compensate_point, InverseMethod};
use crate::number_format::format_coordinate;

/// Options of [`compensate_program`].
#[derive(Debug, Clone)]
pub struct CompensationOptions {
    pub method: InverseMethod,
    /// Largest distance (mm) between a chord and the path it replaces (arcs, and straight moves
    /// the field bends).
    pub chord_tolerance_mm: f64,
    /// Where the tool is before the first move (mm, program coordinates).
    pub start: Vector3<f64>,
    /// Names the model in the header comment.
    pub model_name: String,
}

impl Default for CompensationOptions {
    fn default() -> Self {
        Self {
            method: InverseMethod::FixedPoint,
            chord_tolerance_mm: 0.001,
            start: Vector3::zeros(),
            model_name: "model".into(),
        }
    }
}

/// Something about one input line (1-based line number).
#[derive(Debug, Clone, PartialEq)]
pub struct LineIssue {
    pub line: usize,
    pub message: String,
}

/// What compensation did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CompensationReport {
    pub lines: usize,
    pub motion_lines: usize,
    pub changed_lines: usize,
    /// Lines added by splitting moves and linearising arcs.
    pub added_lines: usize,
    /// Points compensated, and the largest and RMS |commanded − programmed| over them (m).
    pub points: usize,
    pub max_correction_m: f64,
    pub rms_correction_m: f64,
    pub outside_region: Vec<LineIssue>,
    pub malformed: Vec<LineIssue>,
    pub warnings: Vec<LineIssue>,
}

impl CompensationReport {
    /// A few lines for a terminal.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} lines, {} motion lines, {} changed, {} added; {} points compensated, correction max {:.1} µm, rms {:.1} µm",
            self.lines, self.motion_lines, self.changed_lines, self.added_lines, self.points, self.max_correction_m * 1e6, self.rms_correction_m * 1e6
        );
        if !self.outside_region.is_empty() {
            s += &format!(
                "\n{} lines go outside the calibrated region (extrapolated), first at line {}",
                self.outside_region.len(),
                self.outside_region[0].line
            );
        }
        for issue in self.malformed.iter().chain(&self.warnings) {
            s += &format!("\nline {}: {}", issue.line, issue.message);
        }
        s
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Rapid,
    Linear,
    Clockwise,
    CounterClockwise,
}

impl Motion {
    fn code(self) -> &'static str {
        match self {
            Motion::Rapid => "G0",
            Motion::Linear => "G1",
            Motion::Clockwise => "G2",
            Motion::CounterClockwise => "G3",
        }
    }
}

/// G codes that change nothing the compensation depends on (or that it tracks itself).
const HARMLESS_G: &[f64] = &[
    4.0, 17.0, 18.0, 19.0, 20.0, 21.0, 40.0, 49.0, 54.0, 55.0, 56.0, 57.0, 58.0, 59.0, 61.0, 64.0,
    80.0, 90.0, 91.0, 94.0,
];
const AXES: [char; 3] = ['X', 'Y', 'Z'];

struct State<'f> {
    field: &'f dyn ErrorField,
    options: &'f CompensationOptions,
    /// mm per program unit (1 for G21, 25.4 for G20).
    unit_mm: f64,
    absolute: bool,
    plane: ArcPlane,
    motion: Option<Motion>,
    /// The modal motion our output has left the controller in.
    controller_motion: Option<Motion>,
    /// Programmed and commanded (compensated) positions, program units, absolute.
    programmed: Vector3<f64>,
    commanded: Vector3<f64>,
    approach: [f64; 3],
    report: CompensationReport,
    sum_sq: f64,
}

/// Compensate `program` for `field`. Returns the new program (with one header comment) and a
/// report; never fails: what cannot be compensated is passed through and reported.
pub fn compensate_program(
    program: &str,
    field: &dyn ErrorField,
    options: &CompensationOptions,
) -> (String, CompensationReport) {
    let mut st = State {
        field,
        options,
        unit_mm: 1.0,
        absolute: true,
        plane: ArcPlane::XY,
        motion: None,
        controller_motion: None,
        programmed: options.start,
        commanded: options.start,
        approach: [1.0; 3],
        report: CompensationReport::default(),
        sum_sq: 0.0,
    };
    let mut body = String::with_capacity(program.len() + program.len() / 8);
    let mut header_after_percent = false;
    for (index, raw) in program.split_inclusive('\n').enumerate() {
        let number = index + 1;
        st.report.lines += 1;
        let (text, terminator) = split_terminator(raw);
        if index == 0 && text.trim() == "%" {
            header_after_percent = true;
        }
        match parse_block(text) {
            Err(e) => {
                st.report.malformed.push(LineIssue {
                    line: number,
                    message: format!("malformed, passed through untouched: {e}"),
                });
                body.push_str(raw);
            }
            Ok(block) => match st.line(number, text, &block) {
                None => body.push_str(raw),
                Some(lines) => {
                    for l in lines {
                        body.push_str(&l);
                        body.push_str(if terminator.is_empty() {
                            "\n"
                        } else {
                            terminator
                        });
                    }
                    if terminator.is_empty() {
                        body.pop();
                    }
                }
            },
        }
    }
    if st.report.points > 0 {
        st.report.rms_correction_m = (st.sum_sq / st.report.points as f64).sqrt();
    }
    let newline = if program.contains("\r\n") {
        "\r\n"
    } else {
        "\n"
    };
    let header = format!(
        "(metrocell compensate: {}, {} inverse, chord tolerance {} mm, {} of {} motion lines changed){newline}",
        options.model_name.replace(['(', ')'], ""),
        match options.method {
            InverseMethod::FixedPoint => "fixed-point",
            InverseMethod::FirstOrder => "first-order",
        },
        options.chord_tolerance_mm,
        st.report.changed_lines,
        st.report.motion_lines
    );
    let out = if header_after_percent {
        let cut = body.find('\n').map(|i| i + 1).unwrap_or(body.len());
        format!("{}{header}{}", &body[..cut], &body[cut..])
    } else {
        format!("{header}{body}")
    };
    (out, st.report)
}

fn split_terminator(raw: &str) -> (&str, &str) {
    if let Some(t) = raw.strip_suffix("\r\n") {
        (t, "\r\n")
    } else if let Some(t) = raw.strip_suffix('\n') {
        (t, "\n")
    } else {
        (raw, "")
    }
}

impl State<'_> {
    fn warn(&mut self, line: usize, message: String) {
        self.report.warnings.push(LineIssue { line, message });
    }

    /// Process one parsed line: `None` = write it back as it is; `Some(lines)` = replace it.
    ///
    /// The line's G codes set the modes (`modal_codes`); a line with a code compensation does
    /// not model, a dwell or a line without axes passes through; a motion's path is compensated
    /// point by point (`compensated_path`) and the line rewritten (`rewritten_lines`) unless
    /// nothing changed.
    fn line(&mut self, number: usize, text: &str, block: &Block) -> Option<Vec<String>> {
        let (explicit_motion, dwell, unmodelled) = self.modal_codes(block);
        if let Some(m) = explicit_motion {
            self.motion = Some(m);
        }
        let has_axes = AXES.iter().any(|&a| block.word(a).is_some());
        if !unmodelled.is_empty() {
            if has_axes {
                self.warn(number, format!("G{} is not modelled by compensation; the line is written as it is and the positions that follow are taken as programmed", unmodelled.iter().map(|g| format_coordinate(*g, 3)).collect::<Vec<_>>().join(" G")));
                self.take_axes_as_programmed(block);
            }
            if explicit_motion.is_some() {
                self.controller_motion = explicit_motion;
            }
            return None;
        }
        if dwell || !has_axes {
            if explicit_motion.is_some() {
                self.controller_motion = explicit_motion;
            }
            return None;
        }
        let Some(motion) = self.motion else {
            self.warn(
                number,
                "coordinates without a motion mode (G0/G1/G2/G3) before them; written as they are"
                    .into(),
            );
            self.take_axes_as_programmed(block);
            return None;
        };
        self.report.motion_lines += 1;
        let mut target = self.programmed;
        for (k, &a) in AXES.iter().enumerate() {
            if let Some(v) = block.value(a) {
                target[k] = if self.absolute { v } else { target[k] + v };
            }
        }
        let (path, commanded, outside) = self.compensated_path(number, motion, block, target)?;
        let (take_up, commanded) = if motion == Motion::Linear {
            self.split_bent_line(path[0], commanded[0])
        } else {
            (None, commanded)
        };
        if outside {
            self.report.outside_region.push(LineIssue {
                line: number,
                message: "outside the calibrated region: the model is extrapolated".into(),
            });
        }
        let decimals = if self.unit_mm == 1.0 { 4 } else { 5 };
        let unchanged = take_up.is_none()
            && commanded.len() == path.len()
            && commanded
                .iter()
                .zip(&path)
                .all(|(c, p)| same(c, p, decimals))
            && (self.absolute || same(&self.commanded, &self.programmed, decimals))
            && (explicit_motion.is_some() || self.controller_motion == Some(motion));
        let before = self.commanded;
        self.programmed = target;
        self.commanded = *commanded.last().expect("a path has at least its end point");
        if unchanged {
            self.controller_motion = Some(motion);
            return None;
        }
        self.report.changed_lines += 1;
        self.report.added_lines += commanded.len() - 1 + usize::from(take_up.is_some());
        Some(self.rewritten_lines(
            (text, block),
            motion,
            explicit_motion.is_some(),
            before,
            take_up,
            &commanded,
        ))
    }

    /// The motion a line's G codes select, whether it dwells, and the codes compensation does
    /// not model; the plane, unit and distance modes set as the codes say.
    fn modal_codes(&mut self, block: &Block) -> (Option<Motion>, bool, Vec<f64>) {
        let mut explicit_motion = None;
        let mut dwell = false;
        let mut unmodelled = Vec::new();
        for g in block.g_codes() {
            // G numbers are f64 (G38.2 exists); float literal patterns are not allowed, so guards
            #[allow(clippy::redundant_guards)]
            match g {
                x if x == 0.0 => explicit_motion = Some(Motion::Rapid),
                x if x == 1.0 => explicit_motion = Some(Motion::Linear),
                x if x == 2.0 => explicit_motion = Some(Motion::Clockwise),
                x if x == 3.0 => explicit_motion = Some(Motion::CounterClockwise),
                x if x == 4.0 => dwell = true,
                x if x == 17.0 => self.plane = ArcPlane::XY,
                x if x == 18.0 => self.plane = ArcPlane::ZX,
                x if x == 19.0 => self.plane = ArcPlane::YZ,
                x if x == 20.0 => self.unit_mm = 25.4,
                x if x == 21.0 => self.unit_mm = 1.0,
                x if x == 90.0 => self.absolute = true,
                x if x == 91.0 => self.absolute = false,
                x if HARMLESS_G.contains(&x) => {}
                other => unmodelled.push(other),
            }
        }
        (explicit_motion, dwell, unmodelled)
    }

    /// The programmed path of a motion to `target`, each of its points compensated, and whether
    /// any lies outside the calibrated region; None (warned, the positions following the
    /// program) when the path or a point cannot be compensated.
    #[allow(clippy::type_complexity)]
    fn compensated_path(
        &mut self,
        number: usize,
        motion: Motion,
        block: &Block,
        target: Vector3<f64>,
    ) -> Option<(Vec<Vector3<f64>>, Vec<Vector3<f64>>, bool)> {
        let path = match self.path(motion, block, &target) {
            Ok(p) => p,
            Err(e) => {
                self.not_compensated(number, e, target);
                return None;
            }
        };
        let mut commanded = Vec::with_capacity(path.len());
        let mut previous = self.programmed;
        let mut outside = false;
        for p in &path {
            match self.compensate(previous, *p) {
                Ok((c, inside)) => {
                    outside |= !inside;
                    commanded.push(c);
                }
                Err(e) => {
                    self.not_compensated(number, e, target);
                    return None;
                }
            }
            previous = *p;
        }
        Some((path, commanded, outside))
    }

    /// A motion to `target` that could not be compensated: warned, and both positions moved by
    /// the program.
    fn not_compensated(&mut self, number: usize, e: String, target: Vector3<f64>) {
        self.warn(number, format!("not compensated: {e}"));
        self.commanded += target - self.programmed;
        self.programmed = target;
    }

    /// The lines replacing a motion line (`line`: its text and block) from the commanded
    /// position `before`: a take-up move of its own when the bent line needs one, the line
    /// rebuilt to the first commanded point, and a G1 to each further one.
    fn rewritten_lines(
        &mut self,
        (text, block): (&str, &Block),
        motion: Motion,
        explicit: bool,
        before: Vector3<f64>,
        take_up: Option<Vector3<f64>>,
        commanded: &[Vector3<f64>],
    ) -> Vec<String> {
        let decimals = if self.unit_mm == 1.0 { 4 } else { 5 };
        let emitted_motion = if motion == Motion::Rapid {
            Motion::Rapid
        } else {
            Motion::Linear
        };
        let mut lines = Vec::with_capacity(commanded.len() + 1);
        let mut from = before;
        let mut controller_motion = self.controller_motion;
        if let Some(start) = take_up {
            // a line of its own before the programmed one, which keeps its N number, its comment
            // and its other words; the feed the move will run at, so the take-up does not rush
            lines.push(take_up_line(
                &self.axis_words(&from, &start, decimals),
                block.word('F'),
            ));
            from = start;
            controller_motion = Some(Motion::Linear);
        }
        for (i, c) in commanded.iter().enumerate() {
            let words = self.axis_words(&from, c, decimals);
            if i == 0 {
                lines.push(rebuild_first_line(
                    text,
                    block,
                    &words,
                    motion,
                    emitted_motion,
                    explicit,
                    controller_motion,
                ));
            } else {
                let mut l = String::from("G1");
                for (a, v) in &words {
                    l += &format!(" {a}{v}");
                }
                lines.push(l);
            }
            from = *c;
        }
        self.controller_motion = Some(emitted_motion);
        lines
    }

    /// After a line passed through without compensation, both positions follow the program.
    fn take_axes_as_programmed(&mut self, block: &Block) {
        for (k, &a) in AXES.iter().enumerate() {
            if let Some(v) = block.value(a) {
                let target = if self.absolute {
                    v
                } else {
                    self.programmed[k] + v
                };
                self.commanded[k] += target - self.programmed[k];
                self.programmed[k] = target;
            }
        }
    }

    /// Programmed points the move passes through, its end included (program units).
    fn path(
        &self,
        motion: Motion,
        block: &Block,
        target: &Vector3<f64>,
    ) -> Result<Vec<Vector3<f64>>, String> {
        match motion {
            Motion::Rapid | Motion::Linear => Ok(vec![*target]),
            Motion::Clockwise | Motion::CounterClockwise => {
                let centre = match block.value('R') {
                    Some(r) => ArcCentre::Radius(r),
                    None => ArcCentre::Offset(Vector3::new(
                        block.value('I').unwrap_or(0.0),
                        block.value('J').unwrap_or(0.0),
                        block.value('K').unwrap_or(0.0),
                    )),
                };
                let tol = self.options.chord_tolerance_mm / self.unit_mm;
                arc_points(
                    &self.programmed,
                    target,
                    centre,
                    motion == Motion::Clockwise,
                    self.plane,
                    tol,
                    (0.002 / self.unit_mm).max(tol),
                )
            }
        }
    }

    /// Commanded point for programmed point `p` reached from `previous`; also whether `p` is
    /// inside the calibrated region.
    fn compensate(
        &mut self,
        previous: Vector3<f64>,
        p: Vector3<f64>,
    ) -> Result<(Vector3<f64>, bool), String> {
        for k in 0..3 {
            let d = p[k] - previous[k];
            if d != 0.0 {
                self.approach[k] = d.signum();
            }
        }
        let to_m = self.unit_mm * 1e-3;
        let target_m = p * to_m;
        let c_m = compensate_point(self.field, &target_m, &self.approach, self.options.method)
            .map_err(|e| e.0)?;
        let correction = (c_m - target_m).norm();
        self.report.points += 1;
        self.report.max_correction_m = self.report.max_correction_m.max(correction);
        self.sum_sq += correction * correction;
        let inside = self
            .field
            .calibrated_region()
            .is_none_or(|r| r.contains(&target_m));
        Ok((c_m / to_m, inside))
    }

    /// Split a straight move from the current position to programmed `p1` (commanded `c1`) where
    /// the compensated path bends away from the chord: halve until the commanded midpoint is
    /// within the chord tolerance of the chord's midpoint. Returns the take-up move's end point
    /// when the move starts with a reversal, and the move's commanded points, `c1` last (if a
    /// point on the way cannot be compensated, the move is left whole).
    fn split_bent_line(
        &mut self,
        p1: Vector3<f64>,
        c1: Vector3<f64>,
    ) -> (Option<Vector3<f64>>, Vec<Vector3<f64>>) {
        let (p0, mut c0) = (self.programmed, self.commanded);
        let tol = self.options.chord_tolerance_mm / self.unit_mm;
        let approach = self.approach;
        let mut out = Vec::new();
        // a reversal: the start point, compensated for this move's approach directions, is not
        // where the controller is (backlash): take it up with a move of its own first, rather
        // than bending the whole move towards a jump at its start
        let mut take_up = None;
        if let Ok((start, _)) = self.compensate(p0 - (p1 - p0), p0) {
            if (start - c0).norm() > tol {
                take_up = Some(start);
                c0 = start;
            }
        }
        if !self.bisect(p0, c0, p1, c1, tol, 0, &mut out) {
            out.clear();
        }
        self.approach = approach;
        out.push(c1);
        (take_up, out)
    }

    #[allow(clippy::too_many_arguments)]
    fn bisect(
        &mut self,
        p0: Vector3<f64>,
        c0: Vector3<f64>,
        p1: Vector3<f64>,
        c1: Vector3<f64>,
        tol: f64,
        depth: u32,
        out: &mut Vec<Vector3<f64>>,
    ) -> bool {
        const MAX_DEPTH: u32 = 10;
        if depth >= MAX_DEPTH {
            return true;
        }
        let pm = (p0 + p1) / 2.0;
        let Ok((cm, _)) = self.compensate(p0, pm) else {
            return false;
        };
        if (cm - (c0 + c1) / 2.0).norm() <= tol {
            return true;
        }
        if !self.bisect(p0, c0, pm, cm, tol, depth + 1, out) {
            return false;
        }
        out.push(cm);
        self.bisect(pm, cm, p1, c1, tol, depth + 1, out)
    }

    /// Axis words moving the controller from commanded `from` to `to`: every axis whose written
    /// value changes (absolute), or whose increment is not zero (incremental).
    fn axis_words(
        &self,
        from: &Vector3<f64>,
        to: &Vector3<f64>,
        decimals: usize,
    ) -> Vec<(char, String)> {
        let mut words = Vec::new();
        for (k, &a) in AXES.iter().enumerate() {
            if self.absolute {
                let v = format_coordinate(to[k], decimals);
                if v != format_coordinate(from[k], decimals) {
                    words.push((a, v));
                }
            } else {
                let v = format_coordinate(to[k] - from[k], decimals);
                if v != "0" {
                    words.push((a, v));
                }
            }
        }
        words
    }
}

/// The take-up move of a reversal: `G1`, the axis words, and the programmed line's feed word
/// when it has one (no N number, no comment: those stay on the programmed line).
fn take_up_line(words: &[(char, String)], feed: Option<&crate::block::Word>) -> String {
    let mut l = String::from("G1");
    for (a, v) in words {
        l += &format!(" {a}{v}");
    }
    if let Some(f) = feed {
        l += &format!(" F{}", f.number_text);
    }
    l
}

/// The two points are written the same at `decimals` places.
fn same(a: &Vector3<f64>, b: &Vector3<f64>, decimals: usize) -> bool {
    (0..3).all(|k| format_coordinate(a[k], decimals) == format_coordinate(b[k], decimals))
}

/// The first line of a compensated move: the original line with its axis numbers replaced (axes
/// it lacked added before its comment, axes no longer moving dropped), arc words (I J K R)
/// removed and G2/G3 turned into G1 when the arc is linearised, and the motion code written out
/// when the controller's modal motion differs from the program's.
fn rebuild_first_line(
    text: &str,
    block: &Block,
    words: &[(char, String)],
    motion: Motion,
    emitted: Motion,
    explicit: bool,
    controller: Option<Motion>,
) -> String {
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    let arc = matches!(motion, Motion::Clockwise | Motion::CounterClockwise);
    for w in &block.words {
        if AXES.contains(&w.letter) {
            let new = words
                .iter()
                .find(|(a, _)| *a == w.letter)
                .map(|(a, v)| format!("{a}{v}"))
                .unwrap_or_default();
            edits.push((w.span.clone(), new));
        } else if arc && matches!(w.letter, 'I' | 'J' | 'K' | 'R') {
            edits.push((w.span.clone(), String::new()));
        } else if arc && w.letter == 'G' && (w.value == 2.0 || w.value == 3.0) {
            edits.push((w.span.clone(), "G1".into()));
        }
    }
    let missing: Vec<String> = words
        .iter()
        .filter(|(a, _)| block.word(*a).is_none())
        .map(|(a, v)| format!("{a}{v}"))
        .collect();
    let insert_at = block.comment_start.unwrap_or(text.trim_end().len());
    let mut out = String::with_capacity(text.len() + 16);
    let mut at = 0;
    if !explicit && controller != Some(emitted) {
        // the program relied on a modal motion our earlier output changed: say it again
        let after_n = block
            .words
            .iter()
            .find(|w| w.letter == 'N')
            .map(|w| w.span.end)
            .unwrap_or(0);
        out.push_str(&text[..after_n]);
        out.push_str(if after_n == 0 { "" } else { " " });
        out.push_str(emitted.code());
        out.push(' ');
        at = after_n;
        while at < text.len() && text.as_bytes()[at] == b' ' {
            at += 1;
        }
    }
    for (span, new) in edits {
        if span.start < at {
            continue;
        }
        if insert_at <= span.start && at <= insert_at && !missing.is_empty() {
            push_words(&mut out, &text[at..insert_at], &missing);
            at = insert_at;
        }
        out.push_str(&text[at..span.start]);
        out.push_str(&new);
        at = span.end;
    }
    if at <= insert_at && !missing.is_empty() {
        push_words(&mut out, &text[at..insert_at], &missing);
        at = insert_at;
    }
    out.push_str(&text[at..]);
    // removed words leave double spaces; tidy them outside comments
    collapse_spaces(&out, block.comment_start.is_some())
}

fn push_words(out: &mut String, before: &str, words: &[String]) {
    let trimmed = before.trim_end();
    out.push_str(trimmed);
    for w in words {
        if !out.is_empty() && !out.ends_with(' ') {
            out.push(' ');
        }
        out.push_str(w);
    }
    if before.len() > trimmed.len() {
        out.push(' ');
    }
}

fn collapse_spaces(line: &str, has_comment: bool) -> String {
    let code_end = if has_comment {
        line.find(['(', ';']).unwrap_or(line.len())
    } else {
        line.len()
    };
    let (code, rest) = line.split_at(code_end);
    let mut out = String::with_capacity(line.len());
    let mut last_space = false;
    for ch in code.chars() {
        if ch == ' ' {
            if !last_space {
                out.push(ch);
            }
            last_space = true;
        } else {
            out.push(ch);
            last_space = false;
        }
    }
    if rest.is_empty() {
        let t = out.trim_end().len();
        out.truncate(t);
    }
    out.push_str(rest);
    out
}
