//! What the rope's foot does once a round jet has buckled, read from the direction of the axis
//! offset (`jet_axis`) frame after frame. A coiling rope lays its fluid along a circle about the
//! axis, so the direction of its offset turns one way; a folding rope lays it back and forth
//! along a line, so its offset swings through the axis and the direction flips by half a turn.
//! The frames must be close enough for the direction to change by less than half a turn between
//! two of them: every 0.02 s resolves coiling up to 25 turns a second.

use super::jet_axis::AxisSample;
use std::f64::consts::PI;
use std::fmt;

/// Below this largest offset (over D) the rope did not buckle (the jets' criterion).
pub const STRAIGHT_BELOW: f64 = 0.1;
/// At or above this offset (over D) a frame's direction counts: below it the centroid sits too
/// near the axis for its direction to say where the rope is.
pub const OFF_AXIS: f64 = 0.2;
/// The share of the direction's turning that must go one way for the rope to coil.
pub const COILING_COHERENCE: f64 = 0.6;
/// The most the offsets may spread across their main line, against along it, for a fold.
pub const FOLDING_ROUNDNESS: f64 = 0.5;

/// How the rope's foot moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// It stays within [`STRAIGHT_BELOW`] D of the axis.
    Straight,
    /// It leaves the axis by more than that but never by [`OFF_AXIS`] D, too near it for a
    /// direction to read.
    NearAxis,
    /// It swings back and forth through the axis along a line.
    Folding,
    /// It circles the axis one way.
    Coiling,
    /// It left the axis with neither pattern (too few frames off it, or both at once).
    Irregular,
}

impl fmt::Display for Pattern {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Pattern::Straight => "straight",
            Pattern::NearAxis => "near the axis",
            Pattern::Folding => "folding",
            Pattern::Coiling => "coiling",
            Pattern::Irregular => "irregular",
        })
    }
}

/// The rope's motion over a run's frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RopeMotion {
    pub pattern: Pattern,
    /// The largest offset over D, and when (s).
    pub largest_offset_over_d: f64,
    pub largest_at_s: f64,
    /// The first frame off the axis (s), where the pattern is read from; None if none was.
    pub off_axis_from_s: Option<f64>,
    /// Net turns of the offset's direction between consecutive frames off the axis,
    /// counter-clockwise seen from above positive.
    pub turns: f64,
    /// The same turns counted without their sign.
    pub turns_either_way: f64,
    /// The offsets' spread across their main line over that along it, from the first frame off
    /// the axis on, about the axis: 0 on a line through it, 1 on a circle about it.
    pub roundness: f64,
    /// How often the offset crossed the axis along the main line (frames within 0.1 D of the
    /// axis along it not counted).
    pub folds: usize,
    /// From the first frame off the axis to the last frame (s).
    pub duration_s: f64,
}

impl RopeMotion {
    /// Coiling: turns a second (Hz) over [`Self::duration_s`]; folding: folds a second.
    pub fn frequency_hz(&self) -> Option<f64> {
        let per_second = |count: f64| (self.duration_s > 0.0).then(|| count / self.duration_s);
        match self.pattern {
            Pattern::Coiling => per_second(self.turns.abs()),
            Pattern::Folding => per_second(self.folds as f64),
            Pattern::Straight | Pattern::NearAxis | Pattern::Irregular => None,
        }
    }
}

/// The rope's motion in `samples`, in time order. None where no frame has fluid falling
/// through the slab.
pub fn rope_motion(samples: &[AxisSample]) -> Option<RopeMotion> {
    let measured: Vec<(f64, [f64; 2])> = samples.iter().filter_map(|s| s.displacement_over_d.map(|d| (s.time_s, d))).collect();
    let (largest_at_s, largest) = measured.iter().map(|&(t, [x, z])| (t, x.hypot(z))).max_by(|a, b| a.1.total_cmp(&b.1))?;
    let last_s = measured.last().map_or(0.0, |m| m.0);
    let start = measured.iter().position(|(_, [x, z])| x.hypot(*z) >= OFF_AXIS);
    let swung = start.map_or(&[][..], |k| &measured[k..]);
    let (turns, turns_either_way) = turning(swung);
    let (roundness, folds) = spread_and_folds(swung);
    let pattern = if largest < STRAIGHT_BELOW {
        Pattern::Straight
    } else if start.is_none() {
        Pattern::NearAxis
    } else if turns.abs() >= 1.0 && turns.abs() >= COILING_COHERENCE * turns_either_way {
        Pattern::Coiling
    } else if roundness <= FOLDING_ROUNDNESS && folds >= 2 {
        Pattern::Folding
    } else {
        Pattern::Irregular
    };
    let off_axis_from_s = swung.first().map(|m| m.0);
    Some(RopeMotion {
        pattern,
        largest_offset_over_d: largest,
        largest_at_s,
        off_axis_from_s,
        turns,
        turns_either_way,
        roundness,
        folds,
        duration_s: off_axis_from_s.map_or(0.0, |t0| last_s - t0),
    })
}

/// Net and unsigned turns of the direction between consecutive frames both off the axis, each
/// change taken the shorter way round.
fn turning(frames: &[(f64, [f64; 2])]) -> (f64, f64) {
    let direction = |[x, z]: [f64; 2]| (x.hypot(z) >= OFF_AXIS).then(|| x.atan2(z));
    let (mut net, mut either) = (0.0, 0.0);
    for pair in frames.windows(2) {
        if let (Some(a), Some(b)) = (direction(pair[0].1), direction(pair[1].1)) {
            let change = (b - a + PI).rem_euclid(2.0 * PI) - PI;
            net += change;
            either += change.abs();
        }
    }
    (net / (2.0 * PI), either / (2.0 * PI))
}

/// The offsets' roundness about the axis (the square root of the second moment's smaller
/// eigenvalue over its larger), and the crossings of the axis along the main line.
fn spread_and_folds(frames: &[(f64, [f64; 2])]) -> (f64, usize) {
    let (mut xx, mut xz, mut zz) = (0.0, 0.0, 0.0);
    for &(_, [x, z]) in frames {
        xx += x * x;
        xz += x * z;
        zz += z * z;
    }
    let mean = 0.5 * (xx + zz);
    let half_gap = (0.25 * (xx - zz) * (xx - zz) + xz * xz).sqrt();
    let (major, minor) = (mean + half_gap, mean - half_gap);
    if !(major > 0.0) {
        return (0.0, 0);
    }
    let roundness = (minor.max(0.0) / major).sqrt();
    // The main line's direction: the larger eigenvector of [[xx, xz], [xz, zz]].
    let angle = 0.5 * (2.0 * xz).atan2(xx - zz);
    let (ux, uz) = (angle.cos(), angle.sin());
    let mut side = 0.0_f64;
    let mut folds = 0;
    for &(_, [x, z]) in frames {
        let along = x * ux + z * uz;
        if along.abs() >= STRAIGHT_BELOW {
            if side != 0.0 && along.signum() != side {
                folds += 1;
            }
            side = along.signum();
        }
    }
    (roundness, folds)
}
