//! Reader for the MITRE sineMTF target format (`tgt.txt`): a serial number, the
//! patch count, the target's width and height in mm, then per patch a label, a
//! type letter (`d` density patch, `s` sine pattern; either case) and its
//! numbers: x, y, width, height (mm, from the target's top-left corner), then
//! the density (`d`) or the manufacturer's modulation and the frequency in
//! cycles/mm (`s`). Text after `#` is a comment; values are separated by any
//! white space.
//!
//! Mapping: density patches become [`GreyPatch`]es with `density` and
//! reflectance 10^−density; sine patterns become [`SinePatch`]es with
//! `contrast` = the manufacturer modulation and direction x (the MITRE test
//! scan shows vertical bars, the sine varying along the target's width; the
//! scan is the target turned by 180°, which keeps that axis). The format gives
//! neither the sines' mean reflectance nor their phase nor the background:
//! mean is set to [`SINE_MEAN`] and the background to [`BACKGROUND`] (the
//! scan's gaps are darker than its darkest patch); measurement must rely on
//! the modulation only.

use super::{Direction, GreyPatch, Rect, SinePatch, Target};

/// Mean reflectance assumed for sine patterns (the format does not give it).
pub const SINE_MEAN: f64 = 0.5;
/// Background reflectance assumed between patches (density 1.5; not in the format).
pub const BACKGROUND: f64 = 0.031_622_776_601_683_79;

struct Tokens<'a> {
    items: Vec<(usize, &'a str)>,
    pos: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        let items = text
            .lines()
            .enumerate()
            .flat_map(|(n, line)| {
                let body = line.split('#').next().unwrap_or("");
                body.split_whitespace().map(move |t| (n + 1, t))
            })
            .collect();
        Tokens { items, pos: 0 }
    }

    fn next(&mut self, what: &str) -> Result<(usize, &'a str), String> {
        let t = self
            .items
            .get(self.pos)
            .copied()
            .ok_or_else(|| format!("file ends where {what} was expected"))?;
        self.pos += 1;
        Ok(t)
    }

    fn num(&mut self, what: &str) -> Result<f64, String> {
        let (line, t) = self.next(what)?;
        t.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("line {line}: {what} '{t}' is not a number"))
    }
}

/// Parses a sineMTF target description into a [`Target`].
pub fn parse(text: &str) -> Result<Target, String> {
    let mut tk = Tokens::new(text);
    let (_, serial) = tk.next("the target serial number")?;
    let (line, count) = tk.next("the patch count")?;
    let count: usize = count
        .parse()
        .map_err(|_| format!("line {line}: patch count '{count}' is not a whole number"))?;
    let width_mm = tk.num("the target width (mm)")?;
    let height_mm = tk.num("the target height (mm)")?;
    let mut target = Target {
        name: format!("sineMTF {serial}"),
        width_mm,
        height_mm,
        background: BACKGROUND,
        sweeps: vec![],
        patches: vec![],
        greys: vec![],
        fiducials: vec![],
    };
    for k in 0..count {
        let (_, label) = tk.next(&format!("the label of patch {}", k + 1))?;
        let (line, kind) = tk.next(&format!("the type of patch '{label}'"))?;
        let rect = Rect {
            x_mm: tk.num(&format!("patch '{label}' x"))?,
            y_mm: tk.num(&format!("patch '{label}' y"))?,
            width_mm: tk.num(&format!("patch '{label}' width"))?,
            height_mm: tk.num(&format!("patch '{label}' height"))?,
        };
        match kind {
            "d" | "D" => {
                let density = tk.num(&format!("patch '{label}' density"))?;
                target.greys.push(GreyPatch {
                    id: label.to_string(),
                    rect,
                    reflectance: 10f64.powf(-density),
                    density: Some(density),
                });
            }
            "s" | "S" => {
                let contrast = tk.num(&format!("pattern '{label}' modulation"))?;
                let freq_cy_mm = tk.num(&format!("pattern '{label}' frequency"))?;
                target.patches.push(SinePatch {
                    id: label.to_string(),
                    rect,
                    direction: Direction::X,
                    freq_cy_mm,
                    mean: SINE_MEAN,
                    contrast,
                });
            }
            other => {
                return Err(format!(
                    "line {line}: patch '{label}' has type '{other}'; expected d (density) or s (sine)"
                ));
            }
        }
    }
    if let Some(&(line, t)) = tk.items.get(tk.pos) {
        return Err(format!(
            "line {line}: unexpected '{t}' after the {count} patches the header announced"
        ));
    }
    Ok(target)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_file_with_comments_and_case() {
        let t =
            parse("X1 # serial\n2\n10 5\nA d 0 0 4 5 0.3 # grey\n1 S 5 0 5 5 .6 2.0\n").unwrap();
        assert_eq!(t.greys[0].density, Some(0.3));
        assert!((t.greys[0].reflectance - 0.501_187_233_627_272_2).abs() < 1e-12);
        assert_eq!(t.patches[0].freq_cy_mm, 2.0);
        assert_eq!(t.patches[0].contrast, 0.6);
        t.validate().unwrap();
    }

    #[test]
    fn errors_name_the_place() {
        let e = parse("X1\n2\n10 5\nA d 0 0 4 5 0.3\n").unwrap_err();
        assert!(e.contains("file ends"), "{e}");
        let e = parse("X1\n1\n10 5\nA q 0 0 4 5 0.3\n").unwrap_err();
        assert!(e.contains("line 4") && e.contains("'q'"), "{e}");
        let e = parse("X1\n1\n10 5\nA d 0 0 4 five 0.3\n").unwrap_err();
        assert!(e.contains("height") && e.contains("five"), "{e}");
        let e = parse("X1\n1\n10 5\nA d 0 0 4 5 0.3\nB\n").unwrap_err();
        assert!(e.contains("unexpected 'B'"), "{e}");
    }
}
