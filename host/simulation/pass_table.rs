//! The passes of the step schedule, declared once: [`pass_table!`] hands the table to a
//! callback macro, from which come the [`super::backend::Passes`] trait, the CPU's launchers
//! (`cpu::CpuPasses`: the kernel function over the particles with rayon) and the device's
//! (`cuda`'s `GpuPasses`: a launch of the PTX entry the row names). Adding a pass is its
//! kernel, its PTX entries (`coil_kernels::ptx`) and a row here.
//!
//! A row of `passes`: the pass's name and generic physics, its argument struct (in `R`, the
//! topology `T`, and the neighbor visits `N`), the kernel function of one particle index, and
//! the PTX entry's name parts (stem, physics variant, detail, topology; empty parts are left
//! out, the precision is added). A row of `reductions` also gives the particles per range, and
//! which partial sums on the device it fills.

/// Calls `$callback! { passes { rows } reductions { rows } }` with the table (see the module).
macro_rules! pass_table {
    ($callback:ident) => {
        $callback! {
            passes {
                density<K: ::coil_kernels::density::DensityKernel>(::coil_kernels::density::DensityArgs<'_, R, N>)
                    => ::coil_kernels::density::density_pass::<R, K, N>, ["density", K::NAME, "", T::NAME];
                continuity<K: ::coil_kernels::density::DensityKernel>(
                    ::coil_kernels::continuity_molteni2009::ContinuityArgs<'_, R, N>
                ) => ::coil_kernels::continuity_molteni2009::continuity_pass::<R, K, N>, ["continuity", K::NAME, "", T::NAME];
                /// The walls' density, and the fluid's continuity density raised to its sum, with
                /// the spiky kernel, which the divergence-free solves require.
                continuity_floor(::coil_kernels::density::DensityArgs<'_, R, N>)
                    => ::coil_kernels::density::continuity_floor_pass::<R, ::coil_kernels::density::Spiky, N>,
                    ["continuity_floor", "spiky", "", T::NAME];
                density_integration(::coil_kernels::continuity_molteni2009::DensityIntegrationArgs<'_, R>)
                    => ::coil_kernels::continuity_molteni2009::density_integration_pass, ["density_integration", "", "", ""];
                mirrored_wall(::coil_kernels::mirrored_wall::MirroredWallArgs<'_, R, T>)
                    => ::coil_kernels::mirrored_wall::mirrored_wall_pass, ["mirrored_wall", "", "", T::NAME];
                stress<Rh: ::coil_kernels::cross_viscosity::Rheology<R>, G: ::coil_kernels::velocity_gradient::GradientEstimate>(
                    ::coil_kernels::viscosity::stress_andrade2014::StressArgs<'_, R, Rh, G, N>
                ) => ::coil_kernels::viscosity::stress_andrade2014::stress_pass, ["stress", Rh::NAME, G::NAME, T::NAME];
                shear_viscosity<Rh: ::coil_kernels::cross_viscosity::Rheology<R>>(
                    ::coil_kernels::viscosity::laplacian_morris1997::ShearViscosityArgs<'_, R, Rh, N>
                ) => ::coil_kernels::viscosity::laplacian_morris1997::shear_viscosity_pass, ["shear_viscosity", Rh::NAME, "", T::NAME];
                velocity_gradient<Rh: ::coil_kernels::cross_viscosity::Rheology<R>>(
                    ::coil_kernels::viscosity::hourglass_ganzenmuller2015::VelocityGradientArgs<'_, R, Rh, N>
                ) => ::coil_kernels::viscosity::hourglass_ganzenmuller2015::velocity_gradient_pass,
                    ["velocity_gradient", Rh::NAME, "", T::NAME];
                acceleration<Op: ::coil_kernels::viscosity::ViscousOperator<R>>(
                    ::coil_kernels::acceleration::AccelerationArgs<'_, R, Op, N>
                ) => ::coil_kernels::acceleration::acceleration_pass, ["acceleration", Op::NAME, "", T::NAME];
                nozzle(::coil_kernels::nozzle::NozzleArgs<'_, R>) => ::coil_kernels::nozzle::nozzle_pass, ["nozzle", "", "", ""];
                leapfrog(::coil_kernels::leapfrog::LeapfrogArgs<'_, R, T>)
                    => ::coil_kernels::leapfrog::leapfrog_pass, ["leapfrog", "", "", T::NAME];
                shifting(::coil_kernels::shifting_sun2017::ShiftingArgs<'_, R, N>)
                    => ::coil_kernels::shifting_sun2017::shifting_pass, ["shifting", "", "", T::NAME];
                nozzle_shift(::coil_kernels::nozzle::NozzleShiftArgs<'_, R>)
                    => ::coil_kernels::nozzle::nozzle_shift_pass, ["nozzle_shift", "", "", ""];
                shift(::coil_kernels::shifting_sun2017::ShiftArgs<'_, R, T>)
                    => ::coil_kernels::shifting_sun2017::shift_pass, ["shift", "", "", T::NAME];
                predictor(::coil_kernels::viscosity::implicit_weiler2018::PredictorArgs<'_, R>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::predictor_pass, ["predictor", "", "", ""];
                lagged_viscosity<Rh: ::coil_kernels::cross_viscosity::Rheology<R>>(
                    ::coil_kernels::viscosity::implicit_weiler2018::LaggedViscosityArgs<'_, R, Rh, N>
                ) => ::coil_kernels::viscosity::implicit_weiler2018::lagged_viscosity_pass, ["lagged_viscosity", Rh::NAME, "", T::NAME];
                implicit_stress(::coil_kernels::viscosity::implicit_weiler2018::ImplicitStressArgs<'_, R, N>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::implicit_stress_pass, ["implicit_stress", "", "", T::NAME];
                system_block(::coil_kernels::viscosity::implicit_weiler2018::SystemBlockArgs<'_, R, N>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::system_block_pass, ["system_block", "", "", T::NAME];
                system_product(::coil_kernels::viscosity::implicit_weiler2018::SystemProductArgs<'_, R, N>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::system_product_pass, ["system_product", "", "", T::NAME];
                morris_system_block<Nu: ::coil_kernels::viscosity::laplacian_morris1997::ParticleViscosity<R>>(
                    ::coil_kernels::viscosity::laplacian_morris1997::MorrisSystemBlockArgs<'_, R, Nu, N>
                ) => ::coil_kernels::viscosity::laplacian_morris1997::morris_system_block_pass,
                    ["system_block", Nu::OPERATOR_NAME, "", T::NAME];
                morris_system_product<Nu: ::coil_kernels::viscosity::laplacian_morris1997::ParticleViscosity<R>>(
                    ::coil_kernels::viscosity::laplacian_morris1997::MorrisSystemProductArgs<'_, R, Nu, N>
                ) => ::coil_kernels::viscosity::laplacian_morris1997::morris_system_product_pass,
                    ["system_product", Nu::OPERATOR_NAME, "", T::NAME];
                cg_start(::coil_kernels::viscosity::implicit_weiler2018::CgStartArgs<'_, R>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::cg_start_pass, ["cg_start", "", "", ""];
                cg_step(::coil_kernels::viscosity::implicit_weiler2018::CgStepArgs<'_, R>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::cg_step_pass, ["cg_step", "", "", ""];
                cg_direction(::coil_kernels::viscosity::implicit_weiler2018::CgDirectionArgs<'_, R>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::cg_direction_pass, ["cg_direction", "", "", ""];
                viscous_acceleration(::coil_kernels::viscosity::implicit_weiler2018::ViscousAccelerationArgs<'_, R>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::viscous_acceleration_pass, ["viscous_acceleration", "", "", ""];
                dfsph_factor(::coil_kernels::dfsph_bender2017::FactorArgs<'_, R, N>)
                    => ::coil_kernels::dfsph_bender2017::factor_pass, ["dfsph_factor", "", "", T::NAME];
                divergence_error(::coil_kernels::dfsph_bender2017::DivergenceErrorArgs<'_, R, N>)
                    => ::coil_kernels::dfsph_bender2017::divergence_error_pass, ["divergence_error", "", "", T::NAME];
                density_error(::coil_kernels::dfsph_bender2017::DensityErrorArgs<'_, R, N>)
                    => ::coil_kernels::dfsph_bender2017::density_error_pass, ["density_error", "", "", T::NAME];
                dfsph_density_rate(::coil_kernels::dfsph_bender2017::DensityRateArgs<'_, R, N>)
                    => ::coil_kernels::dfsph_bender2017::density_rate_pass, ["dfsph_density_rate", "", "", T::NAME];
                pressure_change(::coil_kernels::dfsph_bender2017::PressureChangeArgs<'_, R, N>)
                    => ::coil_kernels::dfsph_bender2017::pressure_change_pass, ["pressure_change", "", "", T::NAME];
                warm_start(::coil_kernels::dfsph_bender2017::WarmStartArgs<'_, R>)
                    => ::coil_kernels::dfsph_bender2017::warm_start_pass, ["warm_start", "", "", ""];
            }
            reductions {
                /// The two dot products of `args` over the live particles, their ranges' parts
                /// written to `partial` and added in range order: the same on every backend and
                /// thread count. A device waits for them (the solve's next step depends on the
                /// sums); a backend that failed returns NaN and reports the fault when the
                /// schedule ends.
                dots(::coil_kernels::viscosity::implicit_weiler2018::DotArgs<'_, R>)
                    => ::coil_kernels::viscosity::implicit_weiler2018::dot_pass,
                    ::coil_kernels::viscosity::implicit_weiler2018::DOT_RANGE, Dots, ["dots", "", "", ""];
                /// The error of `args` summed over the live fluid particles, and their count, in
                /// range order as [`Passes::dots`].
                error_sums(::coil_kernels::dfsph_bender2017::ErrorSumArgs<'_, R>)
                    => ::coil_kernels::dfsph_bender2017::error_sum_pass,
                    ::coil_kernels::dfsph_bender2017::ERROR_RANGE, ErrorSums, ["error_sums", "", "", ""];
            }
        }
    };
}

pub(crate) use pass_table;
