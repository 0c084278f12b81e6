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

/// Marker shapes; 8 of them against 7 colours, so the first 56 responders
/// each get a pair of their own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Shape {
    Cross,
    TriangleUp,
    Circle,
    Square,
    Diamond,
    Plus,
    TriangleDown,
    Ring,
}

const SHAPES: [Shape; 8] = [
    Shape::Cross,
    Shape::TriangleUp,
    Shape::Circle,
    Shape::Square,
    Shape::Diamond,
    Shape::Plus,
    Shape::TriangleDown,
    Shape::Ring,
];

/// The `n`-th responder's colour and marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Look {
    pub(crate) color: RGBColor,
    pub(crate) shape: Shape,
}

impl Look {
    pub(super) fn nth(n: usize) -> Look {
        Look {
            color: PALETTE[n % PALETTE.len()],
            shape: SHAPES[n % SHAPES.len()],
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
        match self.shape {
            Shape::Cross => (e + Cross::new((0, 0), r, line)).into_dyn(),
            Shape::TriangleUp => (e + TriangleMarker::new((0, 0), d, fill)).into_dyn(),
            Shape::Circle => (e + Circle::new((0, 0), r, fill)).into_dyn(),
            Shape::Square => (e + Rectangle::new([(-r, -r), (r, r)], fill)).into_dyn(),
            Shape::Diamond => {
                (e + Polygon::new(vec![(0, -d), (d, 0), (0, d), (-d, 0)], fill)).into_dyn()
            }
            Shape::Plus => (e
                + PathElement::new(vec![(-r, 0), (r, 0)], line)
                + PathElement::new(vec![(0, -r), (0, r)], line))
            .into_dyn(),
            Shape::TriangleDown => {
                (e + Polygon::new(vec![(-d, -d * 2 / 3), (d, -d * 2 / 3), (0, d)], fill)).into_dyn()
            }
            Shape::Ring => (e + Circle::new((0, 0), r, line)).into_dyn(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_responders_each_get_their_own_colour_and_shape() {
        let looks: Vec<Look> = (0..PALETTE.len() * SHAPES.len()).map(Look::nth).collect();
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
