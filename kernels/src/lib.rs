//! coil's physics: each step of Algorithm 1 of Andrade et al., "SPH Fluids for Viscous Jet
//! Buckling" (SIBGRAPI 2014) as a `no_std` function of one particle index.
//!
//! The CPU backend calls these functions over all particles with rayon; the CUDA backend runs
//! the very same functions as PTX kernels (see `ptx`). Physics is written once, here.
//!
//! Per step: [`cell_grid::hash_pass`], the [`counting_sort`] stages and a gather of every
//! particle field, the [`fluid_cells`] marks, on the CPU the [`neighbor_list`] pass,
//! [`density::density_pass`] (Eq. 5, 6) or, with the continuity equation,
//! [`continuity_molteni2009::continuity_pass`],
//! [`mirrored_wall::mirrored_wall_pass`] (when the scene asks), the viscous operator's pre-pass
//! ([`viscosity::stress_andrade2014::stress_pass`], Eq. 8, 2, 3, for the paper's operator;
//! [`viscosity::laplacian_morris1997::shear_viscosity_pass`] for Morris's operator with the
//! Cross model; [`viscosity::hourglass_ganzenmuller2015::velocity_gradient_pass`] for the
//! paper's operator with hourglass control),
//! [`acceleration::acceleration_pass`] (Eq. 7, 9, Müller's or Morris's Laplacian, hourglass
//! control, gravity),
//! [`nozzle::nozzle_pass`] (jet scenes only),
//! [`continuity_molteni2009::density_integration_pass`] (with the continuity equation),
//! [`shifting_sun2017::shifting_pass`] and [`nozzle::nozzle_shift_pass`] (with particle
//! shifting), [`leapfrog::leapfrog_pass`] and [`shifting_sun2017::shift_pass`] (with particle
//! shifting); then [`diagnostics`] guards the run.
//!
//! With divergence-free pressure the density pass is followed by the factor and the divergence
//! solve's sweeps, and the accelerations by the density solve's ([`dfsph_bender2017`] lists
//! them in order); with implicit viscosity the accelerations are followed by its
//! conjugate-gradient passes ([`viscosity::implicit_weiler2018`]).
#![no_std]
#![allow(clippy::neg_cmp_op_on_partial_ord, reason = "`!(a < b)` is how a check here also refuses NaN")]
#![allow(clippy::needless_range_loop, reason = "a loop over the axes indexes several per-axis arrays at once")]
#![cfg_attr(target_arch = "nvptx64", feature(abi_ptx, link_llvm_intrinsics, stdarch_nvptx))]
// `link_llvm_intrinsics` is how the device reaches NVVM's fast math (see `real`).
#![cfg_attr(target_arch = "nvptx64", allow(internal_features))]

#[cfg(not(target_arch = "nvptx64"))]
extern crate std;

pub mod abi;
pub mod acceleration;
pub mod cell_grid;
pub mod continuity_molteni2009;
pub mod counting_sort;
pub mod cross_viscosity;
pub mod density;
pub mod dfsph_bender2017;
pub mod diagnostics;
pub mod f64_math;
pub mod fluid;
pub mod fluid_cells;
pub mod leapfrog;
pub mod mirrored_wall;
pub mod neighbor_list;
pub mod nozzle;
pub mod real;
pub mod renormalization_bonet1999;
pub mod shifting_sun2017;
pub mod smoothing;
pub mod topology;
pub mod vec3;
pub mod velocity_gradient;
pub mod view;
pub mod viscosity;

#[cfg(any(target_arch = "nvptx64", feature = "host-entries"))]
pub mod ptx;

pub use real::Real;
pub use vec3::{Mat3, SymTensor, Vec3};
