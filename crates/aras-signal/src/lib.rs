//! placeholder
mod butterworth;
mod error;
mod fourier;
mod log;
mod sos;
pub use butterworth::{Butterworth, MAX_ORDER};
pub use error::{FilterError, LogError, ProcessError};
pub use log::*;
pub use sos::{Sos, TransferFunction};
