//! The codecs of the encoder, one module each, plus the shared pieces.

pub mod bits;
pub mod index;
pub mod pca_spline;
pub mod predictive;
pub mod quantizer;
