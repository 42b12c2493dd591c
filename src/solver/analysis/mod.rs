//! What the data can tell: which parameters they identify ([`identifiability`]) and how precisely
//! ([`uncertainty`]).

pub mod identifiability;
pub mod uncertainty;
