//! Where the fluid starts, the walls and the inlets.

use super::MAX_SPEED_M_S;
use super::{Check, Checked};
use crate::scene::{short, Boundary, Domain, InletSettings, Nozzle, NozzleMotion, Scene};

impl Check<'_> {
    /// The initial fluid: blocks, tori and cylinders, each inside the domain.
    pub(super) fn fluid(&self, scene: &Scene) -> Checked {
        let inside = |p: [f64; 3]| scene.domain.contains(p);
        for (k, b) in scene.fluid_blocks.iter().enumerate() {
            for a in 0..3 {
                if !(b.min_m[a] < b.max_m[a]) {
                    return self.fail(&format!("fluid_block[{k}].max_m"), format!("must exceed min_m on every axis (axis {a})"));
                }
            }
            if !inside(b.min_m) || !inside(b.max_m) {
                return self.fail(&format!("fluid_block[{k}]"), "lies outside the domain box".into());
            }
            self.magnitude(&format!("fluid_block[{k}].velocity_m_s"), b.velocity_m_s, MAX_SPEED_M_S, "a speed")?;
        }
        for (k, t) in scene.fluid_tori.iter().enumerate() {
            let field = |f: &str| format!("fluid_torus[{k}].{f}");
            self.positive(&field("major_radius_m"), t.major_radius_m)?;
            self.positive(&field("minor_radius_m"), t.minor_radius_m)?;
            if t.minor_radius_m >= t.major_radius_m {
                return self.fail(
                    &field("minor_radius_m"),
                    format!("must be below major_radius_m ({}) for a ring with a hole", t.major_radius_m),
                );
            }
            let (c, reach) = (t.centre_m, t.major_radius_m + t.minor_radius_m);
            let (lo, hi) =
                ([c[0] - reach, c[1] - t.minor_radius_m, c[2] - reach], [c[0] + reach, c[1] + t.minor_radius_m, c[2] + reach]);
            if !inside(lo) || !inside(hi) {
                return self.fail(&format!("fluid_torus[{k}]"), "lies outside the domain box".into());
            }
            self.magnitude(&field("velocity_m_s"), t.velocity_m_s, MAX_SPEED_M_S, "a speed")?;
        }
        for (k, c) in scene.fluid_cylinders.iter().enumerate() {
            let field = |f: &str| format!("fluid_cylinder[{k}].{f}");
            self.positive(&field("radius_m"), c.radius_m)?;
            self.positive(&field("height_m"), c.height_m)?;
            let (b, r) = (c.base_centre_m, c.radius_m);
            if !inside([b[0] - r, b[1], b[2] - r]) || !inside([b[0] + r, b[1] + c.height_m, b[2] + r]) {
                return self.fail(&format!("fluid_cylinder[{k}]"), "lies outside the domain box".into());
            }
            self.magnitude(&field("velocity_m_s"), c.velocity_m_s, MAX_SPEED_M_S, "a speed")?;
        }
        Ok(())
    }

    pub(super) fn boundaries(&self, boundaries: &[Boundary], d: &Domain) -> Checked {
        for (k, b) in boundaries.iter().enumerate() {
            match *b {
                Boundary::Box { min_m, max_m, .. } => {
                    for a in 0..3 {
                        if !(min_m[a] < max_m[a]) {
                            return self
                                .fail(&format!("boundary[{k}].max_m"), format!("must exceed min_m on every axis (axis {a})"));
                        }
                        let spans = (min_m[a] - d.min_m[a]).abs() < 1e-9 && (max_m[a] - d.max_m[a]).abs() < 1e-9;
                        if d.periodic[a] && !spans {
                            return self.fail(
                                &format!("boundary[{k}]"),
                                format!("axis {a} is periodic, so the box must span the domain along it (it has no walls there)"),
                            );
                        }
                    }
                }
                Boundary::Plate { height_m, min_xz_m, max_xz_m } => {
                    if !height_m.is_finite() {
                        return self.fail(&format!("boundary[{k}].height_m"), format!("must be a finite number, got {height_m}"));
                    }
                    let (lo, hi) = (min_xz_m.unwrap_or([d.min_m[0], d.min_m[2]]), max_xz_m.unwrap_or([d.max_m[0], d.max_m[2]]));
                    if let Some(a) = (0..2).find(|&a| !(lo[a] < hi[a])) {
                        return self.fail(
                            &format!("boundary[{k}].max_xz_m"),
                            format!("must exceed min_xz_m along {} ({} against {})", ["x", "z"][a], hi[a], lo[a]),
                        );
                    }
                }
            }
        }
        Ok(())
    }

    pub(super) fn inlets(&self, scene: &Scene) -> Checked {
        let h = scene.support_radius();
        let inside = |p: [f64; 3]| scene.domain.contains(p);
        for (k, inlet) in scene.inlets.iter().enumerate() {
            if let Some(j) = scene.inlets[..k].iter().position(|earlier| nozzles_overlap(earlier, inlet)) {
                return self.fail(
                    &format!("inlet[{k}]"),
                    format!(
                        "its nozzle overlaps that of inlet[{j}], moving alike, while both inject: the two would lay their particles on top of each other"
                    ),
                );
            }
            let field = |f: &str| format!("inlet[{k}].{f}");
            self.positive(&field("speed_m_s"), inlet.speed_m_s)?;
            if inlet.speed_m_s > MAX_SPEED_M_S {
                return self.fail(
                    &field("speed_m_s"),
                    format!("must be at most {} m/s, got {}", short(MAX_SPEED_M_S), short(inlet.speed_m_s)),
                );
            }
            let end = scene.simulation.end_time_s;
            if !(inlet.start_s >= 0.0 && inlet.start_s < end) {
                return self.fail(
                    &field("start_s"),
                    format!("must be from 0 to before simulation.end_time_s = {} s, got {}", short(end), short(inlet.start_s)),
                );
            }
            if let Some(stop) = inlet.stop_s.filter(|&stop| stop <= inlet.start_s) {
                return self
                    .fail(&field("stop_s"), format!("must be after start_s = {} s, got {}", short(inlet.start_s), short(stop)));
            }
            // Setup lays the nozzle's section on the lattice: it must fit the domain first.
            let d = &scene.domain;
            let extent = (0..3).map(|a| d.max_m[a] - d.min_m[a]).fold(0.0, f64::max);
            let sizes = match inlet.nozzle {
                Nozzle::Circle { radius_m } => vec![("nozzle.radius_m", radius_m, 2.0 * radius_m)],
                Nozzle::Rectangle { width_m, depth_m } => {
                    vec![("nozzle.width_m", width_m, width_m), ("nozzle.depth_m", depth_m, depth_m)]
                }
            };
            for (name, value, size) in sizes {
                self.positive(&field(name), value)?;
                if size > extent {
                    return self.fail(
                        &field(name),
                        format!("makes the nozzle {} m across, wider than the domain box ({} m)", short(size), short(extent)),
                    );
                }
            }
            if !(inlet.wobble_m >= 0.0 && inlet.wobble_m < scene.material.particle_spacing_m) {
                return self.fail(
                    &field("wobble_m"),
                    format!("must be at least 0 and below the particle spacing, got {}", inlet.wobble_m),
                );
            }
            let n2: f64 = inlet.direction.iter().map(|c| c * c).sum();
            if !(n2 > 0.0 && n2.is_finite()) {
                return self.fail(&field("direction"), "must be a non-zero vector".into());
            }
            if !inside(inlet.position_m) {
                return self.fail(&field("position_m"), format!("{:?} lies outside the domain box", inlet.position_m));
            }
            let d = inlet.direction.map(|c| c / n2.sqrt());
            let tube_start = [0, 1, 2].map(|a| inlet.position_m[a] - h * d[a]);
            if !inside(tube_start) {
                return self.fail(
                    &field("position_m"),
                    format!(
                        "the nozzle's tube reaches one support radius ({h} m) upstream of the exit, to {tube_start:?}, outside the domain box; move the nozzle or enlarge the domain"
                    ),
                );
            }
            if let Some(NozzleMotion::Velocity { velocity_m_s }) = &inlet.motion {
                self.magnitude(&field("motion.velocity_m_s"), *velocity_m_s, MAX_SPEED_M_S, "a speed")?;
            }
            if let Some(NozzleMotion::Waypoints { waypoints }) = &inlet.motion {
                if waypoints.is_empty() {
                    return self.fail(&field("motion.waypoints"), "needs at least one [t_s, x_m, y_m, z_m] point".into());
                }
                if waypoints.windows(2).any(|w| !(w[1][0] > w[0][0])) {
                    return self.fail(&field("motion.waypoints"), "times must increase".into());
                }
                if let Some(w) = waypoints.iter().find(|w| !inside([w[1], w[2], w[3]])) {
                    return self.fail(&field("motion.waypoints"), format!("{w:?} lies outside the domain box"));
                }
            }
        }
        Ok(())
    }
}

/// Whether nozzles `a` and `b` overlap while both inject: they move alike (both fixed, or on
/// the same motion), their injection times overlap, and their exits are closer than the sum of
/// their half-widths (a nozzle's exit lies within that distance of its centre whichever way it
/// points).
fn nozzles_overlap(a: &InletSettings, b: &InletSettings) -> bool {
    let half_width = |i: &InletSettings| match i.nozzle {
        Nozzle::Circle { radius_m } => radius_m,
        Nozzle::Rectangle { width_m, depth_m } => 0.5 * width_m.hypot(depth_m),
    };
    let (a_stop, b_stop) = (a.stop_s.unwrap_or(f64::INFINITY), b.stop_s.unwrap_or(f64::INFINITY));
    let together = a.start_s < b_stop && b.start_s < a_stop;
    let distance = (0..3).map(|k| (a.position_m[k] - b.position_m[k]).powi(2)).sum::<f64>().sqrt();
    a.motion == b.motion && together && distance < half_width(a) + half_width(b)
}
