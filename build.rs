//! Build script. With the `web-fonts` feature (the browser's modules, `tools/web.sh`): egui's two default
//! fonts, Hack and Ubuntu Light (from the `epaint_default_fonts` crate, never copied into this
//! repository), subset to the characters a calibration shows, written to `$OUT_DIR/web-fonts/` for
//! `app::web::fonts` to compile in. The full fonts are 671 KB (319 KB gzipped) of the module; the
//! subsets ~160 KB (~75 KB gzipped). Hinting instructions are dropped (skrifa's autohinter hints
//! the outlines instead). The desktop keeps egui's full fonts.
//!
//! Without the feature it does nothing.

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    #[cfg(feature = "web-fonts")]
    web_fonts::write();
    #[cfg(feature = "web-fonts")]
    web_example::write();
}

/// The browser's modules: the bundled example's two CSVs in the compact form of
/// `src/app/example_codec.rs` (its numbers as `f64`s), written to `$OUT_DIR/web-example/` for
/// `app::example` to compile in and decode.
#[cfg(feature = "web-fonts")]
#[allow(dead_code)]
#[path = "src/app/example_codec.rs"]
mod example_codec;

#[cfg(feature = "web-fonts")]
mod web_example {

    pub fn write() {
        let out =
            std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"))
                .join("web-example");
        std::fs::create_dir_all(&out).expect("cannot create $OUT_DIR/web-example");
        println!("cargo::rerun-if-changed=src/app/example_codec.rs");
        for arm in ["left", "right"] {
            let csv = format!("assets/datasets/example/{arm}.csv");
            println!("cargo::rerun-if-changed={csv}");
            let text = std::fs::read_to_string(&csv).unwrap_or_else(|e| panic!("{csv}: {e}"));
            std::fs::write(
                out.join(format!("{arm}.bin")),
                super::example_codec::encode(&text),
            )
            .expect("cannot write the example's compact form");
        }
    }
}

#[cfg(feature = "web-fonts")]
mod web_fonts {
    use read_fonts::{FontRef, collections::IntSet, types::NameId};
    use skera::{DEFAULT_DROP_TABLES, DEFAULT_LAYOUT_FEATURES, Plan, SubsetFlags, subset_font};
    use std::path::PathBuf;

    /// The Unicode ranges kept: what dualcal's and egui's own text use (Greek letters, super- and
    /// subscripts, arrows, ≤ ≈ √ ∂ ∇ ∞, ►, ⏷, ⚠) and what a user's names and paths are likely to
    /// hold in the scripts these two fonts cover (Latin with the European extensions and combining
    /// accents, Greek, Cyrillic). Characters outside draw as a box (egui's
    /// `MissingGlyphPolicy::Tofu`).
    const BLOCKS: &[(u32, u32)] = &[
        (0x0020, 0x007E), // Basic Latin
        (0x00A0, 0x017F), // Latin-1 Supplement, Latin Extended-A
        (0x0192, 0x0192), // ƒ (Windows-1252's 0x83)
        (0x0218, 0x021B), // Romanian ș ț (Latin Extended-B)
        (0x0300, 0x036F), // Combining Diacritical Marks
        (0x0370, 0x03FF), // Greek and Coptic
        (0x0400, 0x04FF), // Cyrillic
        (0x1D2C, 0x1D6A), // modifier letters of the Phonetic Extensions (ᵀ, ᵢ)
        (0x2000, 0x206F), // General Punctuation
        (0x2070, 0x209F), // Superscripts and Subscripts
        (0x20A0, 0x20CF), // Currency Symbols
        (0x2100, 0x214F), // Letterlike Symbols
        (0x2190, 0x21FF), // Arrows
        (0x2200, 0x22FF), // Mathematical Operators
        (0x2300, 0x23FF), // Miscellaneous Technical (egui's ⏴ ⏵ ⏶ ⏷)
        (0x25A0, 0x25FF), // Geometric Shapes (►)
        (0x2600, 0x26FF), // Miscellaneous Symbols (egui's ☀ ⚠)
    ];

    /// The monospace font's (Hack's) narrower set: what the workbench writes in monospace (numbers,
    /// ids, the arms' chains with their arrows, the import report) — ASCII, Latin-1, punctuation,
    /// super- and subscripts, arrows and mathematical operators. egui takes any other character of
    /// monospace text from the next font of the family, Ubuntu Light (`app::web::fonts`), which has
    /// all of `BLOCKS`: a user's Greek or Cyrillic link name still draws, in proportional glyphs.
    /// Its subset: 114 284 → 57 988 bytes (32 KB gzipped).
    const MONOSPACE_BLOCKS: &[(u32, u32)] = &[
        (0x0020, 0x007E), // Basic Latin
        (0x00A0, 0x00FF), // Latin-1 Supplement
        (0x2000, 0x206F), // General Punctuation
        (0x2070, 0x209F), // Superscripts and Subscripts
        (0x2190, 0x21FF), // Arrows
        (0x2200, 0x22FF), // Mathematical Operators
    ];

    fn unicode_set(blocks: &[(u32, u32)]) -> IntSet<u32> {
        let mut unicodes = IntSet::empty();
        for &(first, last) in blocks {
            unicodes.extend(first..=last);
        }
        unicodes
    }

    pub fn write() {
        let dir = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"))
            .join("web-fonts");
        std::fs::create_dir_all(&dir).expect("cannot create $OUT_DIR/web-fonts");
        for (name, bytes, blocks) in [
            (
                "Hack-Regular.ttf",
                epaint_default_fonts::HACK_REGULAR,
                MONOSPACE_BLOCKS,
            ),
            (
                "Ubuntu-Light.ttf",
                epaint_default_fonts::UBUNTU_LIGHT,
                BLOCKS,
            ),
        ] {
            let unicodes = unicode_set(blocks);
            let font = FontRef::new(bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
            let plan = Plan::new(
                &IntSet::empty(),
                &unicodes,
                &font,
                SubsetFlags::SUBSET_FLAGS_NO_HINTING,
                &DEFAULT_DROP_TABLES.iter().copied().collect(),
                &IntSet::all(),
                &DEFAULT_LAYOUT_FEATURES.iter().copied().collect(),
                // Copyright, family, style, unique name, full name, version, PostScript name.
                &(0..=6).map(NameId::from).collect(),
                &[0x0409].into_iter().collect(),
            );
            let subset = subset_font(&font, &plan).unwrap_or_else(|e| panic!("{name}: {e}"));
            std::fs::write(dir.join(name), subset).expect("cannot write a subset font");
        }
        // egui's own icons (3.5 KB): as they are.
        std::fs::write(dir.join("egui-icons.ttf"), epaint_default_fonts::EGUI_ICONS)
            .expect("cannot write egui-icons.ttf");
    }
}
