//! Unit tests of [`RawFrame`](super::RawFrame): planes, lattices, patterns and refused parts.

use super::*;
use crate::photo::Plane;

/// A 7×5 RGGB mosaic whose DN encode the pixel position.
fn mosaic() -> RawFrame {
    let (w, h) = (7, 5);
    let data: Vec<u16> = (0..w * h).map(|i| 100 + i as u16 * 10).collect();
    let black = BlackLevels::repeat(2, 2, 1, vec![100.0, 90.0, 80.0, 70.0]);
    RawFrame::from_mosaic_u16(w, h, CfaPattern::Rggb, black, 440.0, data).unwrap()
}

#[test]
fn lattice_planes_hold_the_pixels_they_name() {
    // Per-site black, so an odd step takes the per-pixel path and an even
    // one the constant-black path; both against the hand formula.
    let f = mosaic();
    assert_eq!(f.green_site(), Some((1, 0)));
    let black = [[100.0, 90.0], [80.0, 70.0]];
    for (offset, step, rect) in [
        ((1, 0), (2, 2), (0, 0, 7, 5)),
        ((0, 0), (3, 3), (0, 0, 7, 5)),
        ((2, 1), (2, 3), (2, 1, 6, 5)),
        ((5, 4), (4, 4), (1, 1, 99, 99)),
    ] {
        let p = f.lattice_plane(offset, step, 0, rect);
        assert_eq!((p.offset, p.step), (offset, step));
        let count = |o: usize, s: usize, hi: usize| (hi.saturating_sub(o)).div_ceil(s);
        assert_eq!(p.width, count(offset.0, step.0, rect.2.min(7)));
        assert_eq!(p.height, count(offset.1, step.1, rect.3.min(5)));
        for j in 0..p.height {
            for i in 0..p.width {
                let (x, y) = (offset.0 + i * step.0, offset.1 + j * step.1);
                let dn = 100.0 + (y * 7 + x) as f64 * 10.0;
                let b = black[y % 2][x % 2];
                let want = (dn - b) / (440.0 - b);
                assert!(
                    (p.get(i, j) as f64 - want).abs() < 1e-6,
                    "{offset:?} {step:?} ({x}, {y})"
                );
            }
        }
    }
}

#[test]
fn bayer_planes_match_a_brute_force_walk_over_every_pixel() {
    let f = mosaic();
    let black = [[100.0, 90.0], [80.0, 70.0]];
    for ch in [RawChannel::R, RawChannel::G, RawChannel::B, RawChannel::All] {
        let planes = f.channel_planes(ch);
        let mut seen = 0;
        for p in &planes {
            assert_eq!(p.step, (2, 2));
            for j in 0..p.height {
                for i in 0..p.width {
                    let (cx, cy) = p.centre(i, j);
                    let (x, y) = ((cx - 0.5) as usize, (cy - 0.5) as usize);
                    let dn = 100.0 + (y * 7 + x) as f64 * 10.0;
                    let b = black[y % 2][x % 2];
                    let want = (dn - b) / (440.0 - b);
                    assert!((p.get(i, j) as f64 - want).abs() < 1e-6);
                    let c = CfaPattern::Rggb.colour_at(x, y);
                    assert!(ch.colours().contains(&c));
                    seen += 1;
                }
            }
        }
        // every pixel of the wanted colours, once
        let expected = (0..5)
            .flat_map(|y| (0..7).map(move |x| (x, y)))
            .filter(|&(x, y)| ch.colours().contains(&CfaPattern::Rggb.colour_at(x, y)))
            .count();
        assert_eq!(seen, expected, "{ch:?}");
    }
    let g = f.channel_planes(RawChannel::G);
    assert_eq!(g.len(), 2);
    assert_eq!((g[0].offset, g[0].width, g[0].height), ((1, 0), 3, 3));
    assert_eq!((g[1].offset, g[1].width, g[1].height), ((0, 1), 4, 2));
    // DN 440 and above are clipped: pixels with 100 + 10 i >= 440 → i >= 34 → one pixel
    assert_eq!(f.clipped_sites(), 1);
}

#[test]
fn windowed_planes_hold_exactly_the_sites_in_the_rectangle_and_spans() {
    let f = mosaic();
    let rect = (1, 1, 6, 5);
    // Row y converts columns [y, y + 3) only.
    let span = |y: usize| (y, y + 3);
    for ch in [RawChannel::R, RawChannel::G, RawChannel::B] {
        let planes = f.channel_groups_within(ch, rect, &span);
        let planes: Vec<&Plane> = planes.iter().flat_map(|g| &g.1).collect();
        let mut seen = 0;
        for p in &planes {
            for j in 0..p.height {
                for i in 0..p.width {
                    let (cx, cy) = p.centre(i, j);
                    let (x, y) = ((cx - 0.5) as usize, (cy - 0.5) as usize);
                    assert!(x >= rect.0 && x < rect.2 && y >= rect.1 && y < rect.3);
                    assert!(ch.colours().contains(&CfaPattern::Rggb.colour_at(x, y)));
                    let want = if x >= y && x < y + 3 {
                        f.value(x, y, 0)
                    } else {
                        0.0
                    };
                    assert!((p.get(i, j) - want).abs() < 1e-6, "({x},{y})");
                    seen += 1;
                }
            }
        }
        let all = (rect.1..rect.3)
            .flat_map(|y| (rect.0..rect.2).map(move |x| (x, y)))
            .filter(|&(x, y)| ch.colours().contains(&CfaPattern::Rggb.colour_at(x, y)))
            .count();
        assert_eq!(seen, all, "{ch:?}: every site of the rectangle once");
    }
}

#[test]
fn the_location_plane_is_one_green_lattice_at_true_positions() {
    let f = mosaic();
    let p = f.location_plane();
    assert_eq!(
        (p.step, p.offset, p.width, p.height),
        ((2, 2), (1, 0), 3, 3)
    );
    for j in 0..p.height {
        for i in 0..p.width {
            let (x, y) = (1 + 2 * i, 2 * j);
            assert_eq!(CfaPattern::Rggb.colour_at(x, y), CfaColour::Green);
            assert!((p.get(i, j) - f.value(x, y, 0)).abs() < 1e-6);
        }
    }
}

#[test]
fn patterns_shift_and_parse() {
    assert_eq!(CfaPattern::Rggb.shifted(1, 0), CfaPattern::Grbg);
    assert_eq!(CfaPattern::Rggb.shifted(0, 1), CfaPattern::Gbrg);
    assert_eq!(CfaPattern::Rggb.shifted(1, 1), CfaPattern::Bggr);
    assert_eq!(CfaPattern::parse("bggr"), Some(CfaPattern::Bggr));
    assert_eq!(CfaPattern::Gbrg.name(), "GBRG");
    assert_eq!(CfaPattern::parse("RGB"), None);
    let x = CfaPattern::parse("GGRGGBGGBGGRBRGRBGGGBGGRGGRGGBRBGBRG").unwrap();
    assert_eq!(x.size(), (6, 6));
}

#[test]
fn inconsistent_parts_are_refused() {
    let b = BlackLevels::uniform(10.0, 1);
    assert!(
        RawFrame::from_mosaic_u16(4, 4, CfaPattern::Rggb, b.clone(), 5.0, vec![0; 16]).is_err()
    );
    assert!(
        RawFrame::from_mosaic_u16(4, 4, CfaPattern::Rggb, b.clone(), 500.0, vec![0; 15]).is_err()
    );
    assert!(RawFrame::from_mosaic_u16(0, 4, CfaPattern::Rggb, b, 500.0, vec![]).is_err());
}
