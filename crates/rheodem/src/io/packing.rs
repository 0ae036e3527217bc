//! Reading sphere packings from text files: one sphere per line, `diameter x y z`
//! (whitespace-separated, SI or model units), `#` comments. A first comment line of the form
//! `# L <edge> …` gives the edge of a periodic cube.

use glam::DVec3;

/// A packing read from text.
#[derive(Clone, Debug, PartialEq)]
pub struct Packing {
    /// Edge of the periodic cube, from a `# L <edge>` header, if present.
    pub box_edge: Option<f64>,
    /// `(diameter, centre)` of each sphere.
    pub spheres: Vec<(f64, DVec3)>,
}

/// Errors of packing parsing, with the 1-based line number.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PackingError {
    /// A line does not hold four numbers.
    #[error("line {line}: expected `diameter x y z` (four numbers), found `{text}`")]
    Malformed {
        /// Line number.
        line: usize,
        /// The offending text.
        text: String,
    },
    /// A diameter is not positive and finite.
    #[error("line {line}: diameter must be positive and finite, found {value}")]
    BadDiameter {
        /// Line number.
        line: usize,
        /// The value found.
        value: f64,
    },
    /// The file holds no sphere.
    #[error("the packing holds no sphere")]
    Empty,
}

/// Parses a packing.
pub fn parse_packing(text: &str) -> Result<Packing, PackingError> {
    let mut box_edge = None;
    let mut spheres = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if let Some(comment) = line.strip_prefix('#') {
            let mut words = comment.split_whitespace();
            if spheres.is_empty() && words.next() == Some("L") {
                box_edge = words.next().and_then(|w| w.parse::<f64>().ok());
            }
            continue;
        }
        if line.is_empty() {
            continue;
        }
        let malformed = || PackingError::Malformed {
            line: k + 1,
            text: raw.to_string(),
        };
        let nums: Vec<f64> = line
            .split_whitespace()
            .map(|w| w.parse::<f64>().map_err(|_| malformed()))
            .collect::<Result<_, _>>()?;
        if nums.len() != 4 || nums.iter().any(|x| !x.is_finite()) {
            return Err(malformed());
        }
        if nums[0] <= 0.0 {
            return Err(PackingError::BadDiameter {
                line: k + 1,
                value: nums[0],
            });
        }
        spheres.push((nums[0], DVec3::new(nums[1], nums[2], nums[3])));
    }
    if spheres.is_empty() {
        return Err(PackingError::Empty);
    }
    Ok(Packing { box_edge, spheres })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_header_and_rows() {
        let p = parse_packing("# L 3.5 N 2\n1.0 0 0 0\n\n0.5 1 2 3\n").expect("valid");
        assert_eq!(p.box_edge, Some(3.5));
        assert_eq!(p.spheres[1], (0.5, DVec3::new(1.0, 2.0, 3.0)));
    }

    #[test]
    fn names_the_bad_line() {
        assert_eq!(
            parse_packing("1 0 0\n"),
            Err(PackingError::Malformed {
                line: 1,
                text: "1 0 0".into()
            })
        );
        assert_eq!(
            parse_packing("1 0 0 0\n-1 0 0 0"),
            Err(PackingError::BadDiameter {
                line: 2,
                value: -1.0
            })
        );
        assert_eq!(parse_packing("# nothing\n"), Err(PackingError::Empty));
    }
}
