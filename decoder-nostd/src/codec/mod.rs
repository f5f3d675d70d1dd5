//! The codecs, one module each, selected by cargo features, and their
//! dispatch: [`Codec`] is a codec section validated once by
//! [`Clip::parse`](crate::Clip::parse) through [`open_codec`].

use crate::error::Error;

#[cfg(feature = "codec-index")]
pub(crate) mod index;
#[cfg(feature = "codec-index")]
pub(crate) mod index_fast;
#[cfg(feature = "codec-pattern")]
pub(crate) mod pattern;
#[cfg(feature = "codec-pca-spline")]
pub(crate) mod pca_spline;
#[cfg(feature = "codec-predictive")]
pub(crate) mod predictive;
#[cfg(feature = "codec-rma")]
pub(crate) mod rma;
#[cfg(feature = "codec-pca-spline")]
pub(crate) mod spline;

#[cfg(feature = "codec-index")]
use index::IndexCodec;
#[cfg(feature = "codec-index")]
use index_fast::FastIndexCodec;
#[cfg(feature = "codec-pattern")]
use pattern::PatternCodec;
#[cfg(feature = "codec-pca-spline")]
use pca_spline::PcaSplineCodec;
#[cfg(feature = "codec-predictive")]
use predictive::PredictiveCodec;
#[cfg(feature = "codec-rma")]
use rma::RmaCodec;

/// The codec section of a clip, validated.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Codec<'a> {
    #[cfg(feature = "codec-index")]
    Index(IndexCodec<'a>),
    /// `index` in its fast layout (§4.6).
    #[cfg(feature = "codec-index")]
    IndexFast(FastIndexCodec<'a>),
    #[cfg(feature = "codec-pca-spline")]
    PcaSpline(PcaSplineCodec<'a>),
    #[cfg(feature = "codec-predictive")]
    Predictive(PredictiveCodec<'a>),
    #[cfg(feature = "codec-pattern")]
    Pattern(PatternCodec<'a>),
    #[cfg(feature = "codec-rma")]
    Rma(RmaCodec<'a>),
    /// Never built: keeps `'a` used when every codec is compiled out.
    #[allow(dead_code)]
    None(core::marker::PhantomData<&'a ()>),
}

/// Validates the codec section `bytes` of id `id` against the header's
/// channel and frame counts (SPEC.md §4–§5b, §11, §12), with `model` the pattern
/// database a show clip reads (§9.2, §11.2); `ContainerNoCodec` for an id
/// this build does not decode.
pub(crate) fn open_codec<'a>(
    id: u8,
    bytes: &'a [u8],
    model: Option<&'a [u8]>,
    channels: usize,
    frames: u32,
) -> Result<Codec<'a>, Error> {
    let _ = (bytes, model, channels, frames);
    match id {
        #[cfg(feature = "codec-index")]
        crate::consts::SECTION_CODEC_INDEX => {
            Ok(Codec::Index(IndexCodec::parse(bytes, channels, frames)?))
        }
        #[cfg(feature = "codec-index")]
        crate::consts::SECTION_CODEC_INDEX_FAST => Ok(Codec::IndexFast(FastIndexCodec::parse(
            bytes, channels, frames,
        )?)),
        #[cfg(feature = "codec-pca-spline")]
        crate::consts::SECTION_CODEC_PCA_SPLINE => Ok(Codec::PcaSpline(PcaSplineCodec::parse(
            bytes, channels, frames,
        )?)),
        #[cfg(feature = "codec-predictive")]
        crate::consts::SECTION_CODEC_PREDICTIVE => Ok(Codec::Predictive(PredictiveCodec::parse(
            bytes, channels, frames,
        )?)),
        #[cfg(feature = "codec-pattern")]
        crate::consts::SECTION_CODEC_PATTERN => Ok(Codec::Pattern(PatternCodec::parse(
            bytes, model, channels, frames,
        )?)),
        #[cfg(feature = "codec-rma")]
        crate::consts::SECTION_CODEC_RMA => {
            Ok(Codec::Rma(RmaCodec::parse(bytes, channels, frames)?))
        }
        _ => Err(Error::ContainerNoCodec),
    }
}
