//! `coil tradeoff`: what each knob that trades speed for accuracy buys, measured on the two
//! Poiseuille cases. Each trial changes one knob of a base channel and records the error
//! against the reference and the wall time; the points no other trial beats on both are the
//! Pareto front. Each trial runs a given number of times: its error must repeat to the bit (the
//! CPU backend is deterministic), its wall time is the median.

use super::case::{operator_label, HOURGLASS_CONTROL};
use super::poiseuille::{cross_poiseuille_in, startup_poiseuille_in};
use super::poiseuille::{Channel, CrossLaw};
use crate::output::plot::{Axis, Chart, Curve, Line, PALETTE};
use crate::scene::{DensityKernelKind, Precision, VelocityGradient, ViscosityOperator, ViscositySolver, ViscousVelocity, Walls};
use crate::statistics::Sorted;
use std::time::Instant;

/// One run of a sweep.
#[derive(Debug, Clone)]
pub struct Trial {
    /// "start-up" (Newtonian, Morris et al.'s series) or "Cross" (steady, shear-thinning).
    pub case: &'static str,
    /// The knob this trial turns away from the base ("base" for the base itself).
    pub knob: &'static str,
    /// The setting, in words.
    pub setting: String,
    pub channel: Channel,
}

/// A trial's outcome.
#[derive(Debug, Clone)]
pub struct Measured {
    pub trial: Trial,
    /// L-infinity error relative to the peak speed; `None` where the guard stopped the run,
    /// which only a trial above the Eq. (10) bound may end with (any other failure ends the
    /// sweep).
    pub error: Option<f64>,
    /// Median wall time of the repeats (s), until the guard stopped the run where it did.
    pub wall_s: f64,
    /// Fastest and slowest repeat (s).
    pub wall_range_s: [f64; 2],
    pub repeats: usize,
    /// Whether no other trial of the same case is at least as good on both and better on one.
    pub pareto: bool,
}

fn operator_word(op: ViscosityOperator) -> &'static str {
    match op {
        ViscosityOperator::Stress => "paper's",
        ViscosityOperator::Laplacian => "Laplacian",
        ViscosityOperator::Morris => "Morris's",
    }
}

/// The trials: the start-up case at 20 across with the Laplacian operator as base (10 across
/// with `quick`), and the Cross case (K = 10 s, n = 0.5) at 10 across with the paper's
/// operator as base.
pub fn trials(quick: bool) -> Vec<Trial> {
    let base_across = if quick { 10 } else { 20 };
    let base = Channel::morris(base_across, ViscosityOperator::Laplacian);
    let mut t = Vec::new();
    let mut add = |case, knob, setting: String, channel| t.push(Trial { case, knob, setting, channel });
    let resolutions: &[usize] = if quick { &[10] } else { &[10, 20, 30] };
    for op in [ViscosityOperator::Laplacian, ViscosityOperator::Morris, ViscosityOperator::Stress] {
        for &across in resolutions {
            let knob = if across == base_across && op == base.operator { "base" } else { "resolution, operator" };
            add("start-up", knob, format!("{across} across, {} operator", operator_word(op)), Channel::morris(across, op));
        }
    }
    let controlled =
        |across| Channel { hourglass_control: HOURGLASS_CONTROL, ..Channel::morris(across, ViscosityOperator::Stress) };
    for &across in resolutions {
        let setting = format!("{across} across, paper's operator, hourglass control {HOURGLASS_CONTROL}");
        add("start-up", "hourglass control", setting, controlled(across));
    }
    let renormalized = |across| Channel {
        velocity_gradient: VelocityGradient::Renormalized,
        ..Channel::morris(across, ViscosityOperator::Stress)
    };
    for &across in resolutions {
        let setting = format!("{across} across, paper's operator, renormalized gradient");
        add("start-up", "velocity gradient", setting, renormalized(across));
    }
    let safety: &[f64] = if quick { &[0.5, 8.0] } else { &[0.5, 0.25, 2.0, 4.0, 8.0] };
    for &f in safety {
        add("start-up", "dt safety factor", format!("{f} x the Eq. (10) bound"), Channel { safety_factor: f, ..base });
    }
    if !quick {
        let above = [
            (ViscosityOperator::Morris, 0.0, [2.0, 4.0]),
            (ViscosityOperator::Stress, 0.0, [4.0, 16.0]),
            (ViscosityOperator::Stress, HOURGLASS_CONTROL, [2.0, 4.0]),
        ];
        for (op, hg, factors) in above {
            for f in factors {
                let channel = Channel { safety_factor: f, hourglass_control: hg, ..Channel::morris(base_across, op) };
                let setting = format!("{f} x the Eq. (10) bound, {}", operator_label(op, hg));
                add("start-up", "dt safety factor", setting, channel);
            }
        }
    }
    // The viscous terms reading v_{n-1/2} double the room above the bound that the full step
    // leaves a viscously damped mode (see `coil_kernels::leapfrog`).
    let half_step = |channel| Channel { viscous_velocity: ViscousVelocity::HalfStep, ..channel };
    let operators = [
        (ViscosityOperator::Laplacian, 0.0, if quick { &[1.0, 8.0][..] } else { &[1.0, 8.0, 12.0][..] }),
        (ViscosityOperator::Morris, 0.0, &[4.0, 8.0]),
        (ViscosityOperator::Stress, 0.0, &[16.0, 32.0]),
        (ViscosityOperator::Stress, HOURGLASS_CONTROL, &[4.0, 8.0]),
    ];
    for (op, hg, factors) in operators.into_iter().take(if quick { 1 } else { 4 }) {
        for &f in factors {
            let channel = Channel { safety_factor: f, hourglass_control: hg, ..Channel::morris(base_across, op) };
            let setting = format!("half step, {f} x the Eq. (10) bound, {}", operator_label(op, hg));
            add("start-up", "viscous velocity", setting, half_step(channel));
        }
    }
    // Implicit viscosity: the viscous term no longer bounds dt; the same operator explicitly at
    // the bound for reference.
    let own_density =
        Channel { velocity_gradient: VelocityGradient::OwnDensity, ..Channel::morris(base_across, ViscosityOperator::Stress) };
    add("start-up", "viscosity solver", "explicit at the bound, paper's operator (own density)".into(), own_density);
    let multiples: &[f64] = if quick { &[10.0] } else { &[1.0, 10.0, 30.0, 100.0] };
    for &m in multiples {
        let channel =
            Channel { solver: ViscositySolver::Implicit, fixed_dt_s: Some(m * own_density.viscous_bound_s()), ..own_density };
        add(
            "start-up",
            "viscosity solver",
            format!("implicit, {m} x the Eq. (10) bound, paper's operator (own density)"),
            channel,
        );
    }
    if !quick {
        for tolerance in [1e-2, 1e-6] {
            let channel = Channel {
                solver: ViscositySolver::Implicit,
                fixed_dt_s: Some(10.0 * own_density.viscous_bound_s()),
                implicit_tolerance: tolerance,
                ..own_density
            };
            add("start-up", "viscosity solver", format!("implicit, 10 x the bound, tolerance {tolerance:e}"), channel);
        }
    }
    let machs: &[f64] = if quick { &[0.1] } else { &[0.1, 1e-3, 1e-4] };
    for &mach in machs {
        let c = base.newtonian_peak() / mach;
        add("start-up", "sound speed", format!("c = {c:.1e} m/s (Mach {mach})"), Channel { sound_speed_m_s: c, ..base });
    }
    let spiky = Channel { density_kernel: DensityKernelKind::Spiky, ..base };
    add("start-up", "density kernel", "spiky".into(), spiky);
    if !quick {
        let c = base.newtonian_peak() / 1e-4;
        add(
            "start-up",
            "density kernel",
            format!("spiky, c = {c:.1e} m/s (Mach 0.0001)"),
            Channel { sound_speed_m_s: c, ..spiky },
        );
    }
    add("start-up", "precision", "f32".into(), Channel { precision: Precision::F32, ..base });
    add("start-up", "walls", "paper's (at rest)".into(), Channel { walls: Walls::Paper, ..base });
    if !quick {
        let stress = Channel::morris(base_across, ViscosityOperator::Stress);
        add("start-up", "precision", "f32, paper's operator".into(), Channel { precision: Precision::F32, ..stress });
        let law = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s: 10.0, n: 0.5 };
        let cross = |across| Channel { cross: Some(law), ..Channel::morris(across, ViscosityOperator::Stress) };
        add("Cross", "base", "10 across".into(), cross(10));
        add("Cross", "resolution", "20 across".into(), cross(20));
        for across in [10, 20] {
            let morris = Channel { operator: ViscosityOperator::Morris, ..cross(across) };
            add("Cross", "operator", format!("{across} across, Morris's operator"), morris);
            let setting = format!("{across} across, hourglass control {HOURGLASS_CONTROL}");
            add("Cross", "hourglass control", setting, Channel { hourglass_control: HOURGLASS_CONTROL, ..cross(across) });
            let setting = format!("{across} across, renormalized gradient");
            add(
                "Cross",
                "velocity gradient",
                setting,
                Channel { velocity_gradient: VelocityGradient::Renormalized, ..cross(across) },
            );
        }
        add("Cross", "precision", "f32".into(), Channel { precision: Precision::F32, ..cross(10) });
        let c = 0.1 * cross(10).sound_speed_m_s;
        add("Cross", "sound speed", format!("c = {c:.1e} m/s (Mach 0.1)"), Channel { sound_speed_m_s: c, ..cross(10) });
        add("Cross", "dt safety factor", "0.5 x the Eq. (10) bound".into(), Channel { safety_factor: 0.5, ..cross(10) });
    }
    t
}

/// What a sweep measured, and why it ended early where it did.
pub struct Sweep {
    pub measured: Vec<Measured>,
    /// The failure that ended the sweep before its last trial.
    pub failure: Option<String>,
}

/// Runs every trial `repeats` times, printing each as it finishes, and marks the Pareto fronts
/// of what was measured. A failure other than the guard stopping a run above the Eq. (10)
/// bound ends the sweep; the trials measured before it are kept.
pub fn run(trials: Vec<Trial>, repeats: usize) -> Sweep {
    sweep(trials, repeats, run_once)
}

/// How one run of a trial ended: its error, or the guard's message.
enum Outcome {
    Finished(f64),
    Stopped(String),
}

/// One run of `trial` and its wall time (s); the guard may stop only a run above the bound.
fn run_once(trial: &Trial) -> Result<(Outcome, f64), String> {
    let started = Instant::now();
    let result = if trial.channel.cross.is_some() {
        cross_poiseuille_in(&trial.channel, None)
    } else {
        startup_poiseuille_in(&trial.channel, None)
    };
    match result {
        Ok(r) => Ok((Outcome::Finished(r.error), r.wall_s)),
        Err(guard) if trial.channel.safety_factor > 1.0 => Ok((Outcome::Stopped(guard), started.elapsed().as_secs_f64())),
        Err(e) => Err(e),
    }
}

/// [`run`] with the runs made by `run_once`.
fn sweep(trials: Vec<Trial>, repeats: usize, mut run_once: impl FnMut(&Trial) -> Result<(Outcome, f64), String>) -> Sweep {
    let mut measured = Vec::with_capacity(trials.len());
    let mut failure = None;
    for trial in trials {
        match measure(&trial, repeats, &mut run_once) {
            Ok((error, wall)) => {
                let (wall_s, wall_range_s) = (wall.median(), [wall.min(), wall.max()]);
                let shown = error_cell(error);
                println!(
                    "{:<9} {:<22} {:<40} error {shown:>8}  {wall_s:>7.1} s ({:.1} to {:.1})",
                    trial.case, trial.knob, trial.setting, wall_range_s[0], wall_range_s[1]
                );
                measured.push(Measured { trial, error, wall_s, wall_range_s, repeats, pareto: false });
            }
            Err(e) => {
                failure = Some(format!("{} / {}: {e}", trial.case, trial.setting));
                break;
            }
        }
    }
    mark_pareto(&mut measured);
    Sweep { measured, failure }
}

/// Runs `trial` `repeats` times: its error (`None` where the guard stopped it), which every
/// repeat must reproduce exactly, and the wall times.
fn measure(
    trial: &Trial,
    repeats: usize,
    run_once: &mut impl FnMut(&Trial) -> Result<(Outcome, f64), String>,
) -> Result<(Option<f64>, Sorted), String> {
    let mut errors = Vec::with_capacity(repeats);
    let mut walls = Vec::with_capacity(repeats);
    for repeat in 0..repeats {
        let (outcome, wall_s) = run_once(trial)?;
        errors.push(match outcome {
            Outcome::Finished(error) => Some(error),
            Outcome::Stopped(guard) => {
                if repeat == 0 {
                    println!("{:<9} {:<22} {:<40} {guard}", trial.case, trial.knob, trial.setting);
                }
                None
            }
        });
        walls.push(wall_s);
    }
    same_every_repeat(&errors)?;
    Ok((errors[0], Sorted::new(walls)))
}

/// Checks that every repeat measured the same error, to the bit: a difference means a run
/// depends on something other than its scene, such as the thread count.
fn same_every_repeat(errors: &[Option<f64>]) -> Result<(), String> {
    let bits = |e: &Option<f64>| e.map(f64::to_bits);
    if errors.iter().all(|e| bits(e) == bits(&errors[0])) {
        return Ok(());
    }
    let shown: Vec<String> = errors.iter().map(|&e| e.map_or("unstable".into(), |e| format!("{e:e}"))).collect();
    Err(format!("the repeats measured different errors ({}): the run is not deterministic", shown.join(", ")))
}

/// Errors within this fraction of each other count as equal: a knob that changes the error
/// only in its third digit buys nothing.
const SAME_ERROR: f64 = 0.01;

/// Marks the trials that no other trial of the same case dominates (error and time both no
/// worse, one better; errors within 1 % equal). A run the guard stopped is on no front.
pub fn mark_pareto(m: &mut [Measured]) {
    let points: Vec<(&str, Option<f64>, f64)> = m.iter().map(|x| (x.trial.case, x.error, x.wall_s)).collect();
    for (k, x) in m.iter_mut().enumerate() {
        let (case, Some(e), w) = points[k] else {
            x.pareto = false;
            continue;
        };
        x.pareto = !points.iter().enumerate().any(|(j, &(c, e2, w2))| {
            let Some(e2) = e2 else { return false };
            let no_worse = e2 <= e * (1.0 + SAME_ERROR);
            let better = e2 < e * (1.0 - SAME_ERROR);
            j != k && c == case && no_worse && w2 <= w && (better || w2 < w)
        });
    }
}

/// The error in a table cell: "unstable" where the guard stopped the run.
fn error_cell(error: Option<f64>) -> String {
    error.map_or("unstable".into(), |e| format!("{e:.4}"))
}

/// The table, Markdown.
pub fn markdown(m: &[Measured]) -> String {
    let repeats = m.first().map_or(0, |x| x.repeats);
    let mut s = format!(
        "# coil tradeoff\n\nEach row changes one knob of the base (start-up: Morris et al.'s channel, Laplacian \
         operator, 20 across, mirrored walls, f64, Mach 0.01, poly6 density, dt at the Eq. (10) bound; Cross: K = 10 s, n = 0.5, \
         paper's operator, 10 across). Error: L-infinity against the reference over the peak speed; \
         \"unstable\": the guard stopped the run (wall s: until then). Wall s: the median of {repeats} runs \
         of each trial (range: fastest to slowest). \
         `*`: on the Pareto front of its case (errors within 1 % count as equal).\n\n\
         | case | knob | setting | error | wall s | range s | front |\n|---|---|---|---:|---:|---:|---|\n",
    );
    for x in m {
        s += &format!(
            "| {} | {} | {} | {} | {:.1} | {:.1} to {:.1} | {} |\n",
            x.trial.case,
            x.trial.knob,
            x.trial.setting,
            error_cell(x.error),
            x.wall_s,
            x.wall_range_s[0],
            x.wall_range_s[1],
            if x.pareto { "*" } else { "" }
        );
    }
    s
}

/// The table, CSV.
pub fn csv(m: &[Measured]) -> String {
    let mut s = String::from("case,knob,setting,error,wall_s,wall_min_s,wall_max_s,repeats,pareto\n");
    for x in m {
        s += &format!(
            "{},\"{}\",\"{}\",{},{:.3},{:.3},{:.3},{},{}\n",
            x.trial.case,
            x.trial.knob,
            x.trial.setting,
            x.error.map_or("unstable".into(), |e| format!("{e:.6e}")),
            x.wall_s,
            x.wall_range_s[0],
            x.wall_range_s[1],
            x.repeats,
            x.pareto
        );
    }
    s
}

/// Error against wall time, log-log: every trial as a point, each case's Pareto front as a line.
pub fn chart(m: &[Measured]) -> Chart {
    let mut series = Vec::new();
    for (k, case) in ["start-up", "Cross"].into_iter().enumerate() {
        let of_case: Vec<&Measured> = m.iter().filter(|x| x.trial.case == case).collect();
        if of_case.is_empty() {
            continue;
        }
        let color = PALETTE[k];
        series.push(Curve {
            label: format!("{case} trials"),
            color,
            points: of_case.iter().filter_map(|x| Some([x.wall_s, x.error?])).collect(),
            line: Line::None,
            marker: 3.0,
        });
        let mut front: Vec<[f64; 2]> = of_case.iter().filter(|x| x.pareto).filter_map(|x| Some([x.wall_s, x.error?])).collect();
        front.sort_by(|a, b| a[0].total_cmp(&b[0]));
        series.push(Curve { label: format!("{case} Pareto front"), color, points: front, line: Line::Solid, marker: 5.0 });
    }
    Chart { title: "error against wall time".into(), x: Axis::log("wall s"), y: Axis::log("L-inf error / peak"), series }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measured(case: &'static str, error: Option<f64>, wall_s: f64) -> Measured {
        let channel = Channel::morris(10, ViscosityOperator::Laplacian);
        let trial = Trial { case, knob: "k", setting: String::new(), channel };
        Measured { trial, error, wall_s, wall_range_s: [wall_s, wall_s], repeats: 1, pareto: false }
    }

    #[test]
    fn the_pareto_front_keeps_what_nothing_beats_on_both_within_a_case() {
        let mut m = vec![
            measured("start-up", Some(0.1), 1.0),
            measured("start-up", Some(0.01), 10.0),
            measured("start-up", Some(0.05), 20.0),
            measured("start-up", Some(0.1), 2.0),
            measured("Cross", Some(0.5), 100.0),
            measured("Cross", Some(0.4999), 200.0),
            measured("start-up", None, 0.5),
        ];
        mark_pareto(&mut m);
        let front: Vec<bool> = m.iter().map(|x| x.pareto).collect();
        // Slower and no better than the first; slower and worse than the second; the Cross
        // trials are compared with Cross trials only, and 0.02 % less error buys nothing; the
        // run the guard stopped, though fastest, is on no front and beats nothing.
        assert_eq!(front, [true, true, false, false, true, false, false]);
        assert_eq!(chart(&m).series[0].points.len(), 4, "the stopped run is not plotted");
        assert!(markdown(&m).contains("| unstable | 0.5 | 0.5 to 0.5 |"), "{}", markdown(&m));
    }

    /// A scripted sweep: each trial's runs give the listed errors (`None`: stopped) and times.
    fn scripted(script: Vec<Vec<Option<f64>>>, repeats: usize) -> (Sweep, usize) {
        let trials: Vec<Trial> =
            (0..script.len()).map(|k| Trial { setting: format!("trial {k}"), ..measured("start-up", None, 0.0).trial }).collect();
        let mut runs = script.into_iter().map(|t| t.into_iter()).collect::<Vec<_>>();
        let mut made = 0;
        let sweep = sweep(trials, repeats, |trial| {
            made += 1;
            let k: usize = trial.setting["trial ".len()..].parse().expect("a scripted trial");
            match runs[k].next().expect("a scripted run") {
                Some(error) if error < 0.0 => Err("a scene that fails".into()),
                Some(error) => Ok((Outcome::Finished(error), made as f64)),
                None => Ok((Outcome::Stopped("stopped".into()), made as f64)),
            }
        });
        (sweep, made)
    }

    #[test]
    fn a_sweep_takes_the_median_time_and_keeps_what_it_measured_before_a_failure() {
        let (done, made) = scripted(vec![vec![Some(0.1); 3], vec![None; 3]], 3);
        assert_eq!((done.measured.len(), made, done.failure), (2, 6, None));
        assert_eq!((done.measured[0].wall_s, done.measured[0].wall_range_s), (2.0, [1.0, 3.0]));
        assert_eq!((done.measured[1].error, done.measured[1].wall_s), (None, 5.0));
        // The second trial fails on its second run: the first is kept, the third never runs.
        let (failed, made) = scripted(vec![vec![Some(0.1); 3], vec![Some(0.2), Some(-1.0)], vec![Some(0.3); 3]], 3);
        assert_eq!((failed.measured.len(), made), (1, 5));
        let why = failed.failure.expect("a failure");
        assert!(why.contains("trial 1") && why.contains("a scene that fails"), "{why}");
        let (drifting, _) = scripted(vec![vec![Some(0.1), Some(0.1)], vec![Some(0.2), Some(0.25)]], 2);
        assert_eq!(drifting.measured.len(), 1);
        assert!(drifting.failure.expect("a failure").contains("not deterministic"));
    }

    #[test]
    fn repeats_must_measure_the_same_error_to_the_bit() {
        assert!(same_every_repeat(&[Some(0.01), Some(0.01), Some(0.01)]).is_ok());
        assert!(same_every_repeat(&[None, None]).is_ok());
        let one_ulp_more = f64::from_bits(0.01f64.to_bits() + 1);
        let drift = same_every_repeat(&[Some(0.01), Some(one_ulp_more), Some(0.01)]).unwrap_err();
        assert!(drift.contains("not deterministic"), "{drift}");
        assert!(same_every_repeat(&[Some(0.01), None]).is_err(), "stopped once, not the other time");
    }
}
