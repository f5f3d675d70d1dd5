//! `mocap encode --target <chip> --budget …`: the chips a clip is made for
//! ([`chips`]), what a clip costs them ([`cost`], a model fitted to QEMU
//! instruction counts by `scripts/cost.sh`, [`fit`]), and the limits a user
//! sets ([`budget`]).

pub mod budget;
mod calibration;
pub mod chips;
pub mod choose;
pub mod cost;
pub mod fit;

pub use budget::{Budget, BudgetError};

use crate::encode::CodecChoice;

/// The codecs `--codec auto --target` tries: those the cost model knows
/// (`scripts/cost.sh` has no `pattern` rows yet).
pub const CANDIDATE_CODECS: [CodecChoice; 4] = [
    CodecChoice::Index,
    CodecChoice::PcaSpline,
    CodecChoice::Predictive,
    CodecChoice::Rma,
];
pub use chips::{chip, chip_names, Chip, Core, CHIPS};
pub use choose::{best_capacity, candidate_label, choose, Candidate};
pub use cost::{predict, predict_capacities, CodecKind, Cost, CostError, Features};
