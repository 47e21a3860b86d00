//! The progress bar: simulated time, steps/s, particles, dt and its limiting term, ETA. Where
//! stderr is not a terminal (a log file, CI) a plain line every 10 s replaces it.

use crate::simulation::model::Model;
use crate::simulation::RunState;
use coil_kernels::Real;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

pub struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
    last_report: Instant,
    last_line: Instant,
    /// Time (s) and steps where this process took the run up, which rates and ETA count from.
    start_time: f64,
    start_steps: u64,
}

impl Progress {
    pub fn new(quiet: bool, start_time: f64, start_steps: u64) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template("{bar:30.cyan/blue} {percent:>3}% {msg} ETA {eta}").expect("a valid template"),
            );
            bar
        });
        let now = Instant::now();
        Self { bar, quiet, last_report: now, last_line: now, start_time, start_steps }
    }

    /// Shows where the run is, at most five times a second; `wall` is this process's time on it.
    pub fn report<R: Real, M: Model<R>>(&mut self, sim: &RunState<R, M>, end: f64, wall: Duration) {
        if self.quiet || self.last_report.elapsed() < Duration::from_millis(200) {
            return;
        }
        self.last_report = Instant::now();
        let rate = (sim.steps - self.start_steps) as f64 / wall.as_secs_f64().max(1e-9);
        let mut solve = sim.solves.last.map_or(String::new(), |s| format!(" | {} CG iterations", s.iterations));
        if let (Some(divergence), Some(density)) = (sim.divergence_solves.last, sim.density_solves.last) {
            solve += &format!(" | pressure {}+{} sweeps", divergence.iterations, density.iterations);
        }
        let line = format!(
            "t = {:.4}/{end} s | {rate:.0} steps/s | {} fluid particles{} | dt {:.2e} s ({}){solve}",
            sim.time,
            sim.fluid_count(),
            if sim.capacity_reached_at.is_some() { " (capacity full: inlets wait)" } else { "" },
            sim.last_dt,
            sim.last_limit
        );
        match &self.bar {
            Some(bar) => {
                bar.set_position((1000.0 * sim.time / end) as u64);
                bar.set_message(line);
            }
            None if self.last_line.elapsed() >= Duration::from_secs(10) => {
                self.last_line = Instant::now();
                let eta = (end - sim.time) / (sim.time - self.start_time).max(1e-300) * wall.as_secs_f64();
                eprintln!("{line} | ETA {eta:.0} s");
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
