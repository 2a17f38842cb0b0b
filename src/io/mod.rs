//! Input and output: Matrix Market, user matrices, HDF5 results with XDMF.

pub mod contact_map;
pub mod figure;
pub mod matrix_market;
pub mod output;
pub mod preview;
pub mod report;
pub mod results;
pub mod series;
pub mod stability;
pub mod user_matrices;
pub mod xdmf;
