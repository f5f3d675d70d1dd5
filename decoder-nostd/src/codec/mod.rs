//! The codecs, one module each, selected by cargo features.

#[cfg(feature = "codec-index")]
pub(crate) mod index;
#[cfg(feature = "codec-pca-spline")]
pub(crate) mod pca_spline;
#[cfg(feature = "codec-predictive")]
pub(crate) mod predictive;
#[cfg(feature = "codec-pca-spline")]
pub(crate) mod spline;
