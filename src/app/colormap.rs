//! An ordered colour map (blue → teal → green → yellow) for error magnitudes; its low end stays
//! visible on the dark viewport background.
//!
//! Control points were chosen by hand to rise monotonically in lightness; values between them are
//! interpolated linearly in sRGB.

/// sRGB control points, evenly spaced over 0..1.
const STOPS: [[f32; 3]; 6] = [
    [0.30, 0.32, 0.80],
    [0.16, 0.52, 0.80],
    [0.10, 0.66, 0.58],
    [0.42, 0.78, 0.34],
    [0.78, 0.86, 0.20],
    [0.99, 0.91, 0.15],
];

/// Colour (sRGB, 0–1) of `t` in 0..1 (clamped).
pub fn srgb(t: f32) -> [f32; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

/// The same colour in linear RGB (for the GPU, which writes into an sRGB target).
pub fn linear(t: f32) -> [f32; 3] {
    srgb(t).map(srgb_to_linear)
}

/// The same colour for egui.
pub fn color32(t: f32) -> egui::Color32 {
    let [r, g, b] = srgb(t);
    egui::Color32::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}

/// Colour (sRGB, 0–1) of a quality flag of `severity` (its size over its threshold, ≥ 1): magenta
/// just past the threshold to red at 8× and beyond (log scale) — hues the error map above never uses.
pub fn flag_srgb(severity: f64) -> [f32; 3] {
    let t = if severity.is_finite() {
        (severity.max(1.0).log2() / 3.0).clamp(0.0, 1.0) as f32
    } else {
        1.0
    };
    let (a, b) = ([0.86, 0.38, 0.98], [1.0, 0.16, 0.16]);
    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * t)
}

/// [`flag_srgb`] in linear RGB.
pub fn flag_linear(severity: f64) -> [f32; 3] {
    flag_srgb(severity).map(srgb_to_linear)
}

/// [`flag_srgb`] for egui.
pub fn flag_color32(severity: f64) -> egui::Color32 {
    let [r, g, b] = flag_srgb(severity);
    egui::Color32::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}

pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

use eframe::egui;

#[cfg(test)]
mod tests {
    use super::*;

    fn luminance(c: [f32; 3]) -> f32 {
        let [r, g, b] = c.map(srgb_to_linear);
        0.2126 * r + 0.7152 * g + 0.0722 * b
    }

    #[test]
    fn lightness_rises_monotonically() {
        let mut last = -1.0;
        for k in 0..=100 {
            let l = luminance(srgb(k as f32 / 100.0));
            assert!(l > last, "not monotone at {k}: {l} <= {last}");
            last = l;
        }
    }

    #[test]
    fn ends_are_clamped_and_nan_is_the_top() {
        assert_eq!(srgb(-1.0), STOPS[0]);
        assert_eq!(srgb(2.0), STOPS[5]);
        assert_eq!(srgb(f32::NAN), STOPS[5]);
    }
}
