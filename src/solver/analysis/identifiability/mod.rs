//! Which parameters can the data identify? The analysis of a Gram matrix ([`analyse`](analyse::analyse)),
//! told whose parameters its columns are ([`columns`]), and its repetition at a step-1 solution
//! (`recheck`).

pub mod analyse;
pub mod columns;
mod recheck;

pub use analyse::{
    FixedParameter, IdentifiabilityReport, NEAR_DEPENDENT_TOL, NEGLIGIBLE_COLUMN, ParameterInfo,
    UNIDENTIFIABLE_TOL, analyse, gram_by_product, gram_by_qr,
};
pub use columns::{Analysis, Columns, analyse_columns};
pub use recheck::{GramMethod, at_solution, at_solution_of_sums, identifiable_at};

#[cfg(test)]
mod tests;
