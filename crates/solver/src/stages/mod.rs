//! The stages of a step, one file each, and the schemes (USF, USL, MUSL)
//! that order them.

pub mod g2p;
pub mod grid_update;
pub mod p2g;
pub mod projection;
pub mod quadrature_mixed;
pub(crate) mod scheme;
pub mod sort;
pub mod stress;
