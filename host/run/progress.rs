//! The progress bar: simulated time, ETA and the solvers' iterations, then the current rate,
//! particles, dt and its limiting term, each line within 80 columns. Where stderr is not a
//! terminal (a log file, CI) a plain line every 10 s replaces it.

use crate::simulation::model::Model;
use crate::simulation::RunState;
use coil_kernels::Real;
use indicatif::{ProgressBar, ProgressStyle};
use std::collections::VecDeque;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Wall time (s) over which the current rate is measured: long enough to span several reports
/// of a slow step, short enough to follow a jet whose particle count grows.
pub const RATE_WINDOW_S: f64 = 5.0;

/// Where a run was at one report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProgressSample {
    /// This process's wall time on the run (s).
    pub wall_s: f64,
    /// Simulated time (s).
    pub time_s: f64,
    pub steps: u64,
    /// Particle-steps done so far.
    pub particle_steps: f64,
    pub fluid_particles: usize,
}

/// The rate and the time left, from the reports of the last [`RATE_WINDOW_S`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Particle-steps a second of wall time.
    pub particle_steps_per_s: f64,
    /// Wall time to the end (s).
    pub remaining_s: f64,
}

/// Estimates from `first` to `last` (reports of one process, in order) the wall time to reach
/// `end_s` of simulated time: the steps left at the recent dt, each over the particles there
/// will be, which grow at the recent rate of fluid particles per simulated second until
/// `fluid_capacity`, done at the recent particle-steps a second. None until the two differ in
/// wall time, simulated time and steps.
pub fn estimate(first: &ProgressSample, last: &ProgressSample, end_s: f64, fluid_capacity: usize) -> Option<Estimate> {
    let wall = last.wall_s - first.wall_s;
    let simulated = last.time_s - first.time_s;
    let steps = last.steps.checked_sub(first.steps).filter(|&s| s > 0)? as f64;
    if !(wall > 0.0 && simulated > 0.0) {
        return None;
    }
    let particle_steps_per_s = (last.particle_steps - first.particle_steps) / wall;
    let particles_per_step = (last.particle_steps - first.particle_steps) / steps;
    let dt = simulated / steps;
    let growth = (last.fluid_particles as f64 - first.fluid_particles as f64).max(0.0) / simulated;
    let room = fluid_capacity.saturating_sub(last.fluid_particles) as f64;
    let left = (end_s - last.time_s).max(0.0);
    // The integral of the particle count over the time left, growing linearly until full.
    let filling = if growth > 0.0 { (room / growth).min(left) } else { left };
    let particle_time = particles_per_step * left + growth * filling * (left - 0.5 * filling);
    if !(particle_steps_per_s > 0.0) {
        return None;
    }
    Some(Estimate { particle_steps_per_s, remaining_s: particle_time / dt / particle_steps_per_s })
}

/// `seconds` as "1h02m", "3m05s" or "42s".
pub fn short_duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, s % 3600 / 60),
    }
}

pub struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
    last_report: Instant,
    last_line: Instant,
    /// The reports of the last [`RATE_WINDOW_S`], oldest first.
    recent: VecDeque<ProgressSample>,
}

impl Progress {
    pub fn new(quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template("{bar:20.cyan/blue} {percent:>3}% {prefix}\n{msg}").expect("a valid template"),
            );
            bar
        });
        let now = Instant::now();
        Self { bar, quiet, last_report: now, last_line: now, recent: VecDeque::new() }
    }

    /// Shows where the run is, at most five times a second; `wall` is this process's time on it
    /// and `particle_steps` the particle-steps it has done.
    pub fn report<R: Real, M: Model<R>>(&mut self, sim: &RunState<R, M>, end: f64, wall: Duration, particle_steps: f64) {
        if self.quiet || self.last_report.elapsed() < Duration::from_millis(200) {
            return;
        }
        self.last_report = Instant::now();
        let now = ProgressSample {
            wall_s: wall.as_secs_f64(),
            time_s: sim.time,
            steps: sim.steps,
            particle_steps,
            fluid_particles: sim.fluid_count(),
        };
        while self.recent.len() > 1 && self.recent[1].wall_s <= now.wall_s - RATE_WINDOW_S {
            self.recent.pop_front();
        }
        self.recent.push_back(now);
        let estimate = self.recent.front().and_then(|first| estimate(first, &now, end, sim.fluid_capacity()));
        let (rate, eta) = match estimate {
            Some(e) => (format!("{:.2e} particle-steps/s", e.particle_steps_per_s), short_duration(e.remaining_s)),
            None => ("-".into(), "-".into()),
        };
        let mut time = format!("t = {:.4}/{end} s, ETA {eta}", sim.time);
        let mut solves = Vec::new();
        if let Some(s) = sim.solves.last {
            solves.push(format!("CG {}", s.iterations));
        }
        if let (Some(divergence), Some(density)) = (sim.divergence_solves.last, sim.density_solves.last) {
            solves.push(format!("sweeps {}+{}", divergence.iterations, density.iterations));
        }
        if !solves.is_empty() {
            time += &format!(" | {}", solves.join(", "));
        }
        let detail = format!(
            "{rate}, {} particles{}, dt {:.2e} s ({})",
            sim.fluid_count(),
            if sim.capacity_reached_at.is_some() { " (full)" } else { "" },
            sim.last_dt,
            sim.last_limit.short()
        );
        match &self.bar {
            Some(bar) => {
                bar.set_position((1000.0 * sim.time / end) as u64);
                bar.set_prefix(time);
                bar.set_message(detail);
            }
            None if self.last_line.elapsed() >= Duration::from_secs(10) => {
                self.last_line = Instant::now();
                eprintln!("{time} | {detail}");
            }
            None => {}
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
