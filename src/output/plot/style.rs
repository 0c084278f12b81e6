//! How a responder looks in the plot: a colour from the Okabe–Ito palette,
//! which stays distinguishable with every common colour-vision deficiency,
//! and a marker shape of its own, so colour is never the only cue.

use plotters::element::{DynElement, IntoDynElement};
use plotters::prelude::*;

/// Okabe & Ito (2008), "Color Universal Design", in the order that keeps
/// the first few furthest apart. Their yellow is left out: it is barely
/// visible on white.
const PALETTE: [RGBColor; 7] = [
    RGBColor(0x00, 0x72, 0xB2), // blue
    RGBColor(0xD5, 0x5E, 0x00), // vermillion
    RGBColor(0x00, 0x9E, 0x73), // bluish green
    RGBColor(0xCC, 0x79, 0xA7), // reddish purple
    RGBColor(0xE6, 0x9F, 0x00), // orange
    RGBColor(0x56, 0xB4, 0xE9), // sky blue
    RGBColor(0x00, 0x00, 0x00), // black
];

/// Marker shapes, drawn by [`Look::marker`]; 8 of them against 7
/// colours, so the first 56 responders each get a pair of their own.
const SHAPES: usize = 8;

/// The `n`-th responder's colour and marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Look {
    pub(crate) color: RGBColor,
    /// Which of the [`SHAPES`], in [`Look::marker`]'s order.
    pub(crate) shape: usize,
}

impl Look {
    pub(super) fn nth(n: usize) -> Look {
        Look {
            color: PALETTE[n % PALETTE.len()],
            shape: n % SHAPES,
        }
    }

    /// The marker centred on `at`, about `r` pixels from centre to edge.
    pub(super) fn marker<'a, DB, C>(&self, at: C, r: i32) -> DynElement<'a, DB, C>
    where
        DB: DrawingBackend + 'a,
        C: Clone + 'a,
    {
        let line = ShapeStyle::from(self.color).stroke_width(2);
        let fill = ShapeStyle::from(self.color).filled();
        let e = EmptyElement::at(at);
        let d = r + 1;
        // A cross, a triangle, a disc, a square, a diamond, a plus, a
        // triangle pointing down, a ring.
        match self.shape {
            0 => (e + Cross::new((0, 0), r, line)).into_dyn(),
            1 => (e + TriangleMarker::new((0, 0), d, fill)).into_dyn(),
            2 => (e + Circle::new((0, 0), r, fill)).into_dyn(),
            3 => (e + Rectangle::new([(-r, -r), (r, r)], fill)).into_dyn(),
            4 => (e + Polygon::new(vec![(0, -d), (d, 0), (0, d), (-d, 0)], fill)).into_dyn(),
            5 => (e
                + PathElement::new(vec![(-r, 0), (r, 0)], line)
                + PathElement::new(vec![(0, -r), (0, r)], line))
            .into_dyn(),
            6 => {
                (e + Polygon::new(vec![(-d, -d * 2 / 3), (d, -d * 2 / 3), (0, d)], fill)).into_dyn()
            }
            _ => (e + Circle::new((0, 0), r, line)).into_dyn(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_responders_each_get_their_own_colour_and_shape() {
        let looks: Vec<Look> = (0..PALETTE.len() * SHAPES).map(Look::nth).collect();
        for (i, a) in looks.iter().enumerate() {
            for b in &looks[i + 1..] {
                assert_ne!(a, b);
            }
        }
        // Neighbours differ in both, so two responders never share a cue.
        for w in looks.windows(2) {
            assert_ne!(w[0].color, w[1].color);
            assert_ne!(w[0].shape, w[1].shape);
        }
    }
}
