//! `--plot` SVGs rendered to pixels by resvg, as a viewer would show them,
//! with the system's DejaVu Sans as sans-serif (`fonts-dejavu-core`,
//! installed by scripts/test.sh). Each PNG is also left in the target
//! directory (`plots/NAME.png`) for a person to look at.

use std::collections::HashMap;
use std::path::PathBuf;

use resvg::{tiny_skia, usvg};

/// A rendered plot.
pub struct Rendered {
    pub png: Vec<u8>,
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// How many pixels have each colour (RGB).
    pub colours: HashMap<[u8; 3], usize>,
    /// RGB of every pixel, row by row.
    pixels: Vec<[u8; 3]>,
}

impl Rendered {
    /// Renders `svg` and writes it as `plots/NAME.png`.
    pub fn of(svg: &str, name: &str) -> Rendered {
        let mut options = usvg::Options::default();
        let fonts = options.fontdb_mut();
        fonts.load_system_fonts();
        let dejavu = fonts
            .faces()
            .any(|f| f.families.iter().any(|(n, _)| n == "DejaVu Sans"));
        assert!(
            dejavu,
            "DejaVu Sans is missing — run `bash scripts/test.sh` (it installs fonts-dejavu-core)"
        );
        fonts.set_sans_serif_family("DejaVu Sans");
        let tree = usvg::Tree::from_str(svg, &options).expect("a valid SVG");
        let size = tree.size().to_int_size();
        let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).unwrap();
        resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
        let png = pixmap.encode_png().unwrap();
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("plots");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{name}.png"));
        std::fs::write(&path, &png).unwrap();
        // The background is opaque white, so premultiplied is plain RGB.
        let pixels: Vec<[u8; 3]> = pixmap
            .pixels()
            .iter()
            .map(|p| [p.red(), p.green(), p.blue()])
            .collect();
        let mut colours = HashMap::new();
        for p in &pixels {
            *colours.entry(*p).or_insert(0) += 1;
        }
        Rendered {
            png,
            path,
            width: size.width(),
            height: size.height(),
            colours,
            pixels,
        }
    }

    /// Pixels of exactly this colour (`0xRRGGBB`).
    pub fn count(&self, rgb: u32) -> usize {
        let [_, r, g, b] = rgb.to_be_bytes();
        self.colours.get(&[r, g, b]).copied().unwrap_or(0)
    }

    /// Pixels in rows `rows` darker than mid grey: drawn text or lines.
    pub fn dark_in_rows(&self, rows: std::ops::Range<u32>) -> usize {
        let w = self.width as usize;
        self.pixels[rows.start as usize * w..rows.end.min(self.height) as usize * w]
            .iter()
            .filter(|p| p.iter().map(|&c| u32::from(c)).sum::<u32>() < 3 * 128)
            .count()
    }
}
