//! The `[material]` table: the liquid, its viscosity and the solve of it.

use super::{Check, Checked};
use super::{
    MAX_CROSS_K_S, MAX_CROSS_N, MAX_GRAVITY_M_S2, MAX_IMPLICIT_ITERATIONS, MAX_PICARD_ITERATIONS, MIN_TOLERANCE,
    REST_DENSITY_KG_M3, SOUND_SPEED_M_S, VISCOSITY_M2_S,
};
use crate::scene::material::{
    ImplicitViscosity, Material, VelocityGradient, ViscosityOperator, ViscositySolver, MAX_HOURGLASS_CONTROL,
};
use crate::scene::short;

impl Check<'_> {
    pub(super) fn material(&self, m: &Material) -> Checked {
        self.within("material.rest_density_kg_m3", m.rest_density_kg_m3, REST_DENSITY_KG_M3, "kg/m^3")?;
        self.within("material.sound_speed_m_s", m.sound_speed_m_s, SOUND_SPEED_M_S, "m/s")?;
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
        self.magnitude("material.gravity_m_s2", m.gravity_m_s2, MAX_GRAVITY_M_S2, "a gravity")?;
        self.within(
            "material.density_diffusion",
            m.density_diffusion,
            (0.0, 1.0),
            "dimensionless; 0.1 is Molteni and Colagrossi's",
        )?;
        let v = &m.viscosity;
        self.within("material.viscosity.nu0_m2_s", v.nu0_m2_s, VISCOSITY_M2_S, "m^2/s")?;
        self.within("material.viscosity.nu_inf_m2_s", v.nu_inf(), VISCOSITY_M2_S, "m^2/s")?;
        if v.nu_inf() > v.nu0_m2_s {
            return self.fail(
                "material.viscosity.nu_inf_m2_s",
                format!("must not exceed nu0_m2_s ({}): the Cross model is shear-thinning, got {}", v.nu0_m2_s, v.nu_inf()),
            );
        }
        self.within("material.viscosity.cross_k_s", v.cross_k_s, (0.0, MAX_CROSS_K_S), "s; 0 is Newtonian")?;
        self.positive("material.viscosity.cross_n", v.cross_n)?;
        if v.cross_n > MAX_CROSS_N {
            return self.fail("material.viscosity.cross_n", format!("must be at most {MAX_CROSS_N}, got {}", short(v.cross_n)));
        }
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
        if v.velocity_gradient != VelocityGradient::Sph && (v.operator != ViscosityOperator::Stress || v.hourglass_control > 0.0)
        {
            return self.fail(
                "material.viscosity.velocity_gradient",
                "\"renormalized\" and \"own_density\" apply to the paper's operator (operator = \"stress\") without hourglass control"
                    .into(),
            );
        }
        if v.solver == ViscositySolver::Implicit {
            let symmetric = match v.operator {
                ViscosityOperator::Stress => v.velocity_gradient == VelocityGradient::OwnDensity && v.hourglass_control == 0.0,
                ViscosityOperator::Morris => true,
                ViscosityOperator::Laplacian => false,
            };
            if !symmetric {
                return self.fail(
                    "material.viscosity.solver",
                    "\"implicit\" solves the paper's operator with velocity_gradient = \"own_density\" (operator = \"stress\") \
                     or Morris's (operator = \"morris\"), the forms whose matrices are symmetric, as conjugate gradients need; \
                     set one of those, or solver = \"explicit\""
                        .into(),
                );
            }
        }
        self.implicit_viscosity(&v.implicit)
    }

    /// The implicit solve's settings, checked whichever solver the scene picks: a `--set` of
    /// the solver must not bring an unchecked value to life.
    pub(super) fn implicit_viscosity(&self, i: &ImplicitViscosity) -> Checked {
        if !(i.tolerance >= MIN_TOLERANCE && i.tolerance < 1.0) {
            return self.fail(
                "material.viscosity.implicit.tolerance",
                format!(
                    "must be from {} to below 1 (a fraction of the first residual; 1e-3 is the default, and below {} f32 rounding decides whether a solve converges), got {}",
                    short(MIN_TOLERANCE),
                    short(MIN_TOLERANCE),
                    short(i.tolerance)
                ),
            );
        }
        if !(1..=MAX_IMPLICIT_ITERATIONS).contains(&i.max_iterations) {
            return self.fail(
                "material.viscosity.implicit.max_iterations",
                format!("must be from 1 to {MAX_IMPLICIT_ITERATIONS}, got {}", i.max_iterations),
            );
        }
        if i.picard_iterations > MAX_PICARD_ITERATIONS {
            return self.fail(
                "material.viscosity.implicit.picard_iterations",
                format!("must be from 0 to {MAX_PICARD_ITERATIONS}, got {}", i.picard_iterations),
            );
        }
        Ok(())
    }
}
