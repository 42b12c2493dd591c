//! What the data can tell: which parameters they identify ([`identifiability`]), how precisely
//! ([`uncertainty`]), and which of those the configurations barely constrain across the workspace
//! ([`weak`]).

pub mod identifiability;
pub mod uncertainty;
pub mod weak;
