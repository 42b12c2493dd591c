//! Closed sets of named values — a method, a split, a unit, a file format — as the engine spells
//! them on the command line and in files.
//!
//! The engine does not parse arguments: each such enum implements [`Choice`] (its values, their
//! spellings, a line of help each) and, through [`choice_strings!`](crate::choice_strings), `FromStr`
//! and `Display`. The command line builds its argument parsers from the same table, so a value's
//! spelling and help are written once.

use std::fmt;

/// A closed set of values with a spelling each.
pub trait Choice: Copy + Sized + 'static {
    /// What the values are (`split`, `QP solver`): used in the message for an unknown spelling.
    const WHAT: &'static str;

    /// Every value, in the order help lists them.
    fn all() -> &'static [Self];

    /// The spelling on the command line (and, for most, in files).
    fn spelling(self) -> &'static str;

    /// Other spellings accepted when parsing.
    fn aliases(self) -> &'static [&'static str] {
        &[]
    }

    /// One line saying what the value does (shown by `--help`).
    fn help(self) -> Option<&'static str> {
        None
    }

    /// The value spelled `text` (or one of its aliases), exactly.
    fn parse_choice(text: &str) -> Result<Self, UnknownChoice> {
        Self::all()
            .iter()
            .copied()
            .find(|v| v.spelling() == text || v.aliases().contains(&text))
            .ok_or_else(|| UnknownChoice {
                what: Self::WHAT,
                given: text.to_string(),
                known: Self::all().iter().map(|v| v.spelling()).collect(),
            })
    }
}

/// A spelling that names no value of a [`Choice`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownChoice {
    /// What the values are.
    pub what: &'static str,
    /// The spelling given.
    pub given: String,
    /// The spellings known.
    pub known: Vec<&'static str>,
}

impl fmt::Display for UnknownChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown {} `{}` (known: ", self.what, self.given)?;
        for (i, k) in self.known.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "`{k}`")?;
        }
        f.write_str(")")
    }
}

impl std::error::Error for UnknownChoice {}

/// `FromStr` and `Display` for types implementing [`Choice`]: parsing by [`Choice::parse_choice`],
/// display as [`Choice::spelling`].
#[macro_export]
macro_rules! choice_strings {
    ($($t:ty),+ $(,)?) => {$(
        impl ::std::str::FromStr for $t {
            type Err = $crate::choice::UnknownChoice;
            fn from_str(text: &str) -> ::std::result::Result<Self, Self::Err> {
                <$t as $crate::choice::Choice>::parse_choice(text)
            }
        }
        impl ::std::fmt::Display for $t {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str($crate::choice::Choice::spelling(*self))
            }
        }
    )+};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Fruit {
        Apple,
        Pear,
    }

    impl Choice for Fruit {
        const WHAT: &'static str = "fruit";
        fn all() -> &'static [Self] {
            &[Fruit::Apple, Fruit::Pear]
        }
        fn spelling(self) -> &'static str {
            match self {
                Fruit::Apple => "apple",
                Fruit::Pear => "pear",
            }
        }
        fn aliases(self) -> &'static [&'static str] {
            match self {
                Fruit::Apple => &["a"],
                Fruit::Pear => &[],
            }
        }
    }
    crate::choice_strings!(Fruit);

    #[test]
    fn parses_spellings_and_aliases_and_names_the_known_ones() {
        assert_eq!("pear".parse::<Fruit>(), Ok(Fruit::Pear));
        assert_eq!("a".parse::<Fruit>(), Ok(Fruit::Apple));
        assert_eq!(Fruit::Apple.to_string(), "apple");
        let err = "Pear".parse::<Fruit>().unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown fruit `Pear` (known: `apple`, `pear`)"
        );
    }
}
