//! What a scene's values must mean, checked once at load: one validator per section, each
//! refusing a value with the field named as `--set` spells it.

use super::{Boundary, Domain, Material, Nozzle, NozzleMotion, Output, Scene, SceneError, ViscosityOperator};
use super::{SimulationSettings, MAX_HOURGLASS_CONTROL};
use crate::simulation::time_step::StabilityBound;

impl Scene {
    pub(super) fn validate(&self, file: &str) -> Result<(), SceneError> {
        let check = Check { file };
        check.material(&self.material)?;
        check.domain(&self.domain, &self.material, self.support_radius())?;
        check.simulation(&self.simulation, &self.material, self.support_radius())?;
        check.output(&self.output)?;
        check.fluid(self)?;
        check.boundaries(&self.boundaries, &self.domain)?;
        check.inlets(self)
    }
}

/// The file whose values are checked, named in every error.
struct Check<'a> {
    file: &'a str,
}

type Checked = Result<(), SceneError>;

impl Check<'_> {
    fn fail(&self, field: &str, reason: String) -> Checked {
        Err(SceneError { file: self.file.into(), field: field.into(), reason })
    }

    fn positive(&self, field: &str, v: f64) -> Checked {
        if v > 0.0 && v.is_finite() {
            Ok(())
        } else {
            self.fail(field, format!("must be a positive number, got {v}"))
        }
    }

    fn material(&self, m: &Material) -> Checked {
        self.positive("material.rest_density_kg_m3", m.rest_density_kg_m3)?;
        self.positive("material.sound_speed_m_s", m.sound_speed_m_s)?;
        self.positive("material.particle_spacing_m", m.particle_spacing_m)?;
        if !(m.support_radius_factor > 1.0 && m.support_radius_factor <= 4.0) {
            return self.fail(
                "material.support_radius_factor",
                format!(
                    "must be above 1 (walls one spacing away would be invisible) and at most 4; 2 gives about 33 neighbors, got {}",
                    m.support_radius_factor
                ),
            );
        }
        if m.gravity_m_s2.iter().any(|g| !g.is_finite()) {
            return self.fail("material.gravity_m_s2", "must be finite".into());
        }
        let v = &m.viscosity;
        self.positive("material.viscosity.nu0_m2_s", v.nu0_m2_s)?;
        self.positive("material.viscosity.nu_inf_m2_s", v.nu_inf())?;
        if v.nu_inf() > v.nu0_m2_s {
            return self.fail(
                "material.viscosity.nu_inf_m2_s",
                format!("must not exceed nu0_m2_s ({}): the Cross model is shear-thinning, got {}", v.nu0_m2_s, v.nu_inf()),
            );
        }
        if !(v.cross_k_s >= 0.0 && v.cross_k_s.is_finite()) {
            return self.fail("material.viscosity.cross_k_s", format!("must be zero or positive, got {}", v.cross_k_s));
        }
        self.positive("material.viscosity.cross_n", v.cross_n)?;
        if v.operator == ViscosityOperator::Laplacian && !v.is_newtonian() {
            return self.fail(
                "material.viscosity.operator",
                "the Laplacian operator is Newtonian (nu0 only); set cross_k_s = 0, or use operator = \"morris\" or \"stress\" for a Cross fluid".into(),
            );
        }
        if !(0.0..=MAX_HOURGLASS_CONTROL).contains(&v.hourglass_control) {
            return self.fail(
                "material.viscosity.hourglass_control",
                format!("must be from 0 to {MAX_HOURGLASS_CONTROL}, got {}", v.hourglass_control),
            );
        }
        if v.hourglass_control > 0.0 && v.operator != ViscosityOperator::Stress {
            return self.fail(
                "material.viscosity.hourglass_control",
                "controls the paper's operator (operator = \"stress\"); the Laplacian operators have no odd-even mode to control"
                    .into(),
            );
        }
        Ok(())
    }

    /// `h`: the support radius (m).
    fn domain(&self, d: &Domain, m: &Material, h: f64) -> Checked {
        for a in 0..3 {
            if !(d.min_m[a] < d.max_m[a]) || !d.min_m[a].is_finite() || !d.max_m[a].is_finite() {
                return self.fail("domain.max_m", format!("must exceed domain.min_m on every axis (axis {a})"));
            }
        }
        let cells: f64 = (0..3).map(|a| ((d.max_m[a] - d.min_m[a]) / h).ceil()).product();
        if cells > 2.0e8 {
            return self.fail(
                "domain",
                format!("needs {cells:.3e} grid cells of edge h = {h} m; shrink the domain or coarsen the spacing"),
            );
        }
        for a in (0..3).filter(|&a| d.periodic[a]) {
            let length = d.max_m[a] - d.min_m[a];
            if length * (1.0 + crate::cpu::neighbor_grid::PERIODIC_ROUNDING) < 3.0 * h {
                return self.fail(
                    "domain.periodic",
                    format!(
                        "axis {a} is periodic but the domain is {length} m long along it, less than 3 support radii ({} m)",
                        3.0 * h
                    ),
                );
            }
            let spacings = length / m.particle_spacing_m;
            if (spacings - spacings.round()).abs() > 1e-6 * spacings {
                return self.fail(
                    "domain.periodic",
                    format!(
                        "axis {a} is periodic, so its length {length} m must be a whole number of particle spacings ({} m) for the lattice to close across the seam; it is {spacings:.4} spacings",
                        m.particle_spacing_m
                    ),
                );
            }
        }
        Ok(())
    }

    /// `h`: the support radius (m).
    fn simulation(&self, s: &SimulationSettings, m: &Material, h: f64) -> Checked {
        self.positive("simulation.end_time_s", s.end_time_s)?;
        let ts = &s.time_step;
        self.positive("simulation.time_step.safety_factor", ts.safety_factor)?;
        if ts.safety_factor > 1.0 && !ts.allow_above_stability_bound {
            return self.fail(
                "simulation.time_step.safety_factor",
                format!(
                    "{} would put dt above the stability bound of Eq. (10); use at most 1, or set \
                     simulation.time_step.allow_above_stability_bound = true to run anyway",
                    ts.safety_factor
                ),
            );
        }
        if let Some(dt) = ts.fixed_s {
            self.positive("simulation.time_step.fixed_s", dt)?;
            let (limit_dt, limit) = StabilityBound::new(h, m.sound_speed_m_s, m.viscosity.nu0_m2_s).dt();
            if dt > limit_dt && !ts.allow_above_stability_bound {
                return self.fail(
                    "simulation.time_step.fixed_s",
                    format!(
                        "{dt:e} s is above the stability bound of Eq. (10), {limit_dt:.3e} s (set by the {limit}); \
                         above it explicit leap-frog is not known to be stable. Lower it, remove it for the automatic step, or set \
                         simulation.time_step.allow_above_stability_bound = true to run anyway"
                    ),
                );
            }
        }
        Ok(())
    }

    fn output(&self, o: &Output) -> Checked {
        if let Some(e) = o.every_s {
            self.positive("output.every_s", e)?;
        }
        if o.every_steps == Some(0) {
            return self.fail("output.every_steps", "must be at least 1".into());
        }
        if o.formats.is_empty() {
            return self.fail("output.formats", "must name at least one of \"vtu\", \"ply\", \"xyz\"".into());
        }
        Ok(())
    }

    /// The initial fluid: blocks, tori and cylinders, each inside the domain.
    fn fluid(&self, scene: &Scene) -> Checked {
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
        }
        for (k, c) in scene.fluid_cylinders.iter().enumerate() {
            let field = |f: &str| format!("fluid_cylinder[{k}].{f}");
            self.positive(&field("radius_m"), c.radius_m)?;
            self.positive(&field("height_m"), c.height_m)?;
            let (b, r) = (c.base_centre_m, c.radius_m);
            if !inside([b[0] - r, b[1], b[2] - r]) || !inside([b[0] + r, b[1] + c.height_m, b[2] + r]) {
                return self.fail(&format!("fluid_cylinder[{k}]"), "lies outside the domain box".into());
            }
        }
        Ok(())
    }

    fn boundaries(&self, boundaries: &[Boundary], d: &Domain) -> Checked {
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

    fn inlets(&self, scene: &Scene) -> Checked {
        let h = scene.support_radius();
        let inside = |p: [f64; 3]| scene.domain.contains(p);
        for (k, inlet) in scene.inlets.iter().enumerate() {
            let field = |f: &str| format!("inlet[{k}].{f}");
            self.positive(&field("speed_m_s"), inlet.speed_m_s)?;
            match inlet.nozzle {
                Nozzle::Circle { radius_m } => self.positive(&field("nozzle.radius_m"), radius_m)?,
                Nozzle::Rectangle { width_m, depth_m } => {
                    self.positive(&field("nozzle.width_m"), width_m)?;
                    self.positive(&field("nozzle.depth_m"), depth_m)?;
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
