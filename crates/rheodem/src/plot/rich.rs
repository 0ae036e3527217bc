//! Labels with subscripts and superscripts: `R_c`, `p*_φ`, `T_macro*`, `f_a^max` are drawn
//! as `R` with a lowered, smaller `c` (and so on), for titles, axis labels, legends and
//! colour bars alike. A `_` or `^` takes the letters and digits that follow it (Greek
//! included), or a group in braces (`V_{b,0}`); anything else is drawn as written.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// How a run of text sits on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shift {
    /// On the baseline, full size.
    Normal,
    /// Lowered and smaller.
    Sub,
    /// Raised and smaller.
    Sup,
}

/// Splits a label into runs of text and how each sits on the line.
pub fn runs(label: &str) -> Vec<(String, Shift)> {
    let mut out: Vec<(String, Shift)> = Vec::new();
    let push = |out: &mut Vec<(String, Shift)>, c: char, shift: Shift| match out.last_mut() {
        Some((text, s)) if *s == shift => text.push(c),
        _ => out.push((c.to_string(), shift)),
    };
    let chars: Vec<char> = label.chars().collect();
    let mut k = 0;
    while k < chars.len() {
        let c = chars[k];
        let shift = match c {
            '_' => Shift::Sub,
            '^' => Shift::Sup,
            _ => Shift::Normal,
        };
        if shift == Shift::Normal || k + 1 == chars.len() {
            push(&mut out, c, Shift::Normal);
            k += 1;
            continue;
        }
        let start = k + 1;
        let end = if chars[start] == '{' {
            match chars[start..].iter().position(|&c| c == '}') {
                Some(close) => {
                    for &c in &chars[start + 1..start + close] {
                        push(&mut out, c, shift);
                    }
                    k = start + close + 1;
                    continue;
                }
                None => start,
            }
        } else {
            chars[start..]
                .iter()
                .position(|c| !c.is_alphanumeric())
                .map_or(chars.len(), |n| start + n)
        };
        if end == start {
            // A lone `_` or `^`: drawn as written.
            push(&mut out, c, Shift::Normal);
            k += 1;
            continue;
        }
        for &c in &chars[start..end] {
            push(&mut out, c, shift);
        }
        k = end;
    }
    out
}

/// The label as plain text, without the markup (for places that cannot draw runs).
pub fn plain(label: &str) -> String {
    runs(label).into_iter().map(|(t, _)| t).collect()
}

/// Where a label is drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// `at` is the left end of the baseline's line box (its top-left corner).
    Left,
    /// `at` is the centre of the line box.
    Centre,
}

/// Size (pixels) of the runs' parts at font size `size`.
fn part_size(shift: Shift, size: f64) -> f64 {
    match shift {
        Shift::Normal => size,
        Shift::Sub | Shift::Sup => 0.72 * size,
    }
}

/// Drawn length (pixels) of `label` at font size `size`.
pub fn width<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    label: &str,
    size: f64,
) -> u32 {
    runs(label)
        .iter()
        .map(|(t, s)| {
            let style = TextStyle::from(("sans-serif", part_size(*s, size)).into_font());
            area.estimate_text_size(t, &style).map_or(0, |(w, _)| w)
        })
        .sum()
}

/// Draws `label` at font size `size` (pixels) in `colour`, horizontally, or rotated to read
/// upwards (`vertical`, for a y-axis label), from `at` as `align` says.
pub fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    label: &str,
    at: (i32, i32),
    size: f64,
    colour: &RGBColor,
    align: Align,
    vertical: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let total = width(area, label, size) as i32;
    let half_height = (0.5 * size) as i32;
    // Start of the baseline run's box (top-left when horizontal; bottom-left when it reads
    // upwards) and the direction along the line.
    let (mut along, across) = match (align, vertical) {
        (Align::Left, false) => (at.0, at.1),
        (Align::Centre, false) => (at.0 - total / 2, at.1 - half_height),
        (Align::Left, true) => (at.1, at.0),
        (Align::Centre, true) => (at.1 + total / 2, at.0 - half_height),
    };
    for (text, shift) in runs(label) {
        let s = part_size(shift, size);
        // Offset across the line, towards its bottom: a subscript's box sits lower.
        let drop = match shift {
            Shift::Normal => 0.0,
            Shift::Sub => 0.42 * size,
            Shift::Sup => -0.12 * size,
        } as i32;
        let mut style = ("sans-serif", s).into_font().color(colour);
        let w = area
            .estimate_text_size(&text, &TextStyle::from(("sans-serif", s).into_font()))
            .map_or(0, |(w, _)| w) as i32;
        let pos = if vertical {
            style = style.transform(FontTransform::Rotate270);
            (across + drop, along)
        } else {
            (along, across + drop)
        };
        area.draw(&Text::new(
            text,
            pos,
            style.pos(Pos::new(HPos::Left, VPos::Top)),
        ))?;
        along += if vertical { -w } else { w };
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subscripts_and_superscripts_are_split_off() {
        use Shift::*;
        let r = |s: &str| runs(s);
        assert_eq!(
            r("R_c (m)"),
            [
                ("R".into(), Normal),
                ("c".into(), Sub),
                (" (m)".into(), Normal)
            ]
        );
        assert_eq!(
            r("p*_φ)"),
            [
                ("p*".into(), Normal),
                ("φ".into(), Sub),
                (")".into(), Normal)
            ]
        );
        assert_eq!(
            r("T_macro* = f_a^max"),
            [
                ("T".into(), Normal),
                ("macro".into(), Sub),
                ("* = f".into(), Normal),
                ("a".into(), Sub),
                ("max".into(), Sup)
            ]
        );
        assert_eq!(r("V_{b,0}"), [("V".into(), Normal), ("b,0".into(), Sub)]);
        // A lone marker is text.
        assert_eq!(r("a _ b_"), [("a _ b_".into(), Normal)]);
        assert_eq!(plain("S_c* = S_c/d_p"), "Sc* = Sc/dp");
    }
}
