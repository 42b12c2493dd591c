//! Length and angle units of a dataset's files.

/// Unit of lengths in a dataset's files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LengthUnit {
    #[default]
    Mm,
    M,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn mm_per_unit(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1000.0,
        }
    }

    /// The name used in files (`mm` or `m`).
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::M => "m",
        }
    }

    /// Parse a file name of the unit (exact, lowercase).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "mm" => Some(LengthUnit::Mm),
            "m" => Some(LengthUnit::M),
            _ => None,
        }
    }

    /// A value in this unit, in mm.
    pub fn to_mm(self, v: f64) -> f64 {
        v * self.mm_per_unit()
    }

    /// A value in mm, in this unit.
    pub fn from_mm(self, v_mm: f64) -> f64 {
        match self {
            LengthUnit::Mm => v_mm,
            LengthUnit::M => v_mm / 1000.0,
        }
    }
}

/// Unit of angles in a dataset's files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum AngleUnit {
    Deg,
    #[default]
    Rad,
}

impl AngleUnit {
    /// The name used in files (`deg` or `rad`).
    pub fn name(self) -> &'static str {
        match self {
            AngleUnit::Deg => "deg",
            AngleUnit::Rad => "rad",
        }
    }

    /// Parse a file name of the unit (exact, lowercase).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "deg" => Some(AngleUnit::Deg),
            "rad" => Some(AngleUnit::Rad),
            _ => None,
        }
    }

    /// A value in this unit, in rad.
    pub fn to_rad(self, v: f64) -> f64 {
        match self {
            AngleUnit::Deg => v.to_radians(),
            AngleUnit::Rad => v,
        }
    }

    /// A value in rad, in this unit.
    pub fn from_rad(self, v_rad: f64) -> f64 {
        match self {
            AngleUnit::Deg => v_rad.to_degrees(),
            AngleUnit::Rad => v_rad,
        }
    }
}

/// The units of a dataset's files (`[units]` in `dataset.toml`). In memory everything is mm and rad.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Units {
    pub length: LengthUnit,
    pub angle: AngleUnit,
}

impl Units {
    /// Millimetres and radians (the internal units).
    pub const MM_RAD: Units = Units {
        length: LengthUnit::Mm,
        angle: AngleUnit::Rad,
    };
    /// Millimetres and degrees (what a robot controller and a tracker usually print).
    pub const MM_DEG: Units = Units {
        length: LengthUnit::Mm,
        angle: AngleUnit::Deg,
    };
}
