//! The `coil` command line: its arguments and the commands behind them.

pub mod args;
pub mod commands;
pub mod pov;
pub mod render;
pub mod surface;
