//! The codecs of the encoder, one module each, plus the shared pieces.

pub mod index;
pub mod quantizer;
