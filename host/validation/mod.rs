//! Validation against independent references (analytic solutions, published experiments and
//! other codes): `coil validate` and its tests.

pub mod case;
pub mod divergence_free;
pub mod huppert;
pub mod hydrostatic;
pub mod jet;
pub mod jet_axis;
pub mod poiseuille;
pub mod rope_motion;
pub mod snapshot;
pub mod suite;
pub mod taylor_green;
pub mod torus;
pub mod tradeoff;
pub mod viscous_thread;
