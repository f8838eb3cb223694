//! The raw adapter on a real Canon 550D DNG (Magic Lantern, via tinydng):
//! levels, active area, CFA order and every plane checked against the file's
//! own tags and samples, read here independently with a hand-written TIFF tag
//! reader and 14-bit unpacker (the `tiff` crate refuses CFA data); plus the missing-optics-metadata case.

use std::path::{Path, PathBuf};
use sweepmtf::photo::exif::read_facts;
use sweepmtf::photo::pitch::{self, PitchSource};
use sweepmtf::photo::raw::{CfaPattern, RawChannel, decode_raw};

fn realdata(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real")).join(rel)
}

fn dng() -> PathBuf {
    realdata("raw/tinydng_colorchart_canon550d_magiclantern.dng")
}

/// What the file says about itself, read without rawler.
struct Truth {
    full_width: usize,
    black: u32,
    white: u32,
    /// top, left, bottom, right
    active: [usize; 4],
    cfa: Vec<u8>,
    strip_offset: usize,
    bits: usize,
    bytes: Vec<u8>,
}

/// Values of IFD0 entry `tag` (integer types only), read by hand from the TIFF bytes.
fn tag(bytes: &[u8], want: u16) -> Vec<u32> {
    let le = &bytes[..2] == b"II";
    let u16_at = |o: usize| {
        let b = [bytes[o], bytes[o + 1]];
        if le {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        }
    };
    let u32_at = |o: usize| {
        let b = [bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]];
        if le {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    };
    let ifd = u32_at(4) as usize;
    for k in 0..u16_at(ifd) as usize {
        let e = ifd + 2 + 12 * k;
        if u16_at(e) != want {
            continue;
        }
        let (typ, count) = (u16_at(e + 2), u32_at(e + 4) as usize);
        let size = match typ {
            1 | 7 => 1,
            3 => 2,
            4 => 4,
            t => panic!("tag {want}: type {t}"),
        };
        let at = if size * count <= 4 {
            e + 8
        } else {
            u32_at(e + 8) as usize
        };
        return (0..count)
            .map(|i| match size {
                1 => bytes[at + i] as u32,
                2 => u16_at(at + 2 * i) as u32,
                _ => u32_at(at + 4 * i),
            })
            .collect();
    }
    panic!("tag {want} not in IFD0")
}

fn truth() -> Truth {
    let bytes = std::fs::read(dng()).unwrap();
    assert_eq!(tag(&bytes, 259), [1], "uncompressed");
    assert_eq!(tag(&bytes, 273).len(), 1, "one strip");
    let a = tag(&bytes, 50829);
    Truth {
        full_width: tag(&bytes, 256)[0] as usize,
        black: tag(&bytes, 50714)[0],
        white: tag(&bytes, 50717)[0],
        active: [a[0] as usize, a[1] as usize, a[2] as usize, a[3] as usize],
        cfa: tag(&bytes, 33422).iter().map(|&c| c as u8).collect(),
        strip_offset: tag(&bytes, 273)[0] as usize,
        bits: tag(&bytes, 258)[0] as usize,
        bytes,
    }
}

impl Truth {
    /// DN of full-image pixel (x, y): MSB-first packed samples, rows byte-aligned.
    fn dn(&self, x: usize, y: usize) -> u32 {
        let row_bytes = (self.full_width * self.bits).div_ceil(8);
        let bit = x * self.bits;
        let start = self.strip_offset + y * row_bytes + bit / 8;
        let mut acc: u64 = 0;
        for k in 0..4 {
            acc = (acc << 8) | *self.bytes.get(start + k).unwrap_or(&0) as u64;
        }
        let shift = 32 - (bit % 8) - self.bits;
        ((acc >> shift) & ((1 << self.bits) - 1)) as u32
    }
}

#[test]
fn levels_active_area_and_cfa_order_come_from_the_file() {
    let t = truth();
    assert_eq!((t.black, t.white), (2056, 15000), "README values");
    let f = decode_raw(&dng()).unwrap();
    assert_eq!(f.width, t.active[3] - t.active[1]);
    assert_eq!(f.height, t.active[2] - t.active[0]);
    assert_eq!((f.width, f.height), (1734, 1156));
    assert!(f.black.levels.iter().all(|&b| b == t.black as f64));
    assert_eq!(f.white, vec![t.white as f64]);
    // DNG CFAPattern is anchored at the active area's corner: 0 = R, 1 = G, 2 = B.
    let letters: String = t.cfa.iter().map(|&c| ['R', 'G', 'B'][c as usize]).collect();
    assert_eq!(letters, "RGGB");
    assert_eq!(f.cfa, Some(CfaPattern::Rggb));
    assert_eq!(f.samples_per_pixel, 1);
    assert_eq!(f.bits_per_sample, 14);
    assert_eq!(f.make, "Canon");
    assert_eq!(f.model, "Canon EOS Kiss X4");
    assert_eq!(f.format, "DNG");
}

#[test]
fn every_plane_holds_the_files_own_samples_black_subtracted_and_scaled() {
    let t = truth();
    let f = decode_raw(&dng()).unwrap();
    let (left, top) = (t.active[1], t.active[0]);
    let scale = 1.0 / (t.white as f64 - t.black as f64);
    let want = |x: usize, y: usize| (t.dn(left + x, top + y) as f64 - t.black as f64) * scale;

    let expect = [
        (RawChannel::R, vec![(0, 0)]),
        (RawChannel::G, vec![(1, 0), (0, 1)]),
        (RawChannel::B, vec![(1, 1)]),
        (RawChannel::All, vec![(0, 0), (1, 0), (0, 1), (1, 1)]),
    ];
    for (ch, offsets) in expect {
        let planes = f.channel_planes(ch);
        assert_eq!(planes.len(), offsets.len(), "{ch:?}");
        for (p, off) in planes.iter().zip(offsets) {
            assert_eq!(p.offset, off, "{ch:?}");
            assert_eq!(p.step, (2, 2));
            assert_eq!((p.width, p.height), (867, 578));
            assert_eq!(p.data.len(), 867 * 578);
            // a sparse but complete walk: every 7th row, every sample of it
            for j in (0..p.height).step_by(7).chain([p.height - 1]) {
                for i in 0..p.width {
                    let (x, y) = (off.0 + 2 * i, off.1 + 2 * j);
                    let got = p.get(i, j) as f64;
                    assert!((got - want(x, y)).abs() < 1e-6, "{ch:?} ({x},{y}): {got}");
                }
            }
        }
    }
    let groups = f.channel_groups(RawChannel::All);
    let names: Vec<&str> = groups.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["r", "g", "b"]);
    assert_eq!(groups[1].1.len(), 2);
}

#[test]
fn clipped_sites_match_an_independent_count() {
    let t = truth();
    let f = decode_raw(&dng()).unwrap();
    let (mut clipped, mut max) = (0usize, 0u32);
    for y in t.active[0]..t.active[2] {
        for x in t.active[1]..t.active[3] {
            let d = t.dn(x, y);
            max = max.max(d);
            clipped += (d >= t.white) as usize;
        }
    }
    assert_eq!(f.clipped_sites(), clipped, "max DN {max}");
    assert_eq!(f.clipped_fraction(), clipped as f64 / (1734.0 * 1156.0));
}

#[test]
fn missing_optics_metadata_is_absent_with_warnings_not_absurd_values() {
    let f = decode_raw(&dng()).unwrap();
    for facts in [f.facts.clone(), read_facts(&dng()).unwrap()] {
        assert_eq!(facts.make.as_deref(), Some("Canon"));
        assert_eq!(facts.model.as_deref(), Some("Canon EOS Kiss X4"));
        assert_eq!(facts.f_number, None);
        assert_eq!(facts.focal_length_mm, None);
        assert!(facts.from_raw);
        for tag in ["FNumber", "FocalLength"] {
            assert!(
                facts.warnings.iter().any(|w| w.starts_with(tag)),
                "{tag}: {:?}",
                facts.warnings
            );
        }
        let p = pitch::resolve(&facts, f.width, f.height, None);
        assert_eq!(p.pitch_mm, None);
        assert_eq!(p.source, PitchSource::None);
        assert!(!p.notes.is_empty());
        let e = pitch::auto_model_specs(&facts, 0.0043, 550e-6).unwrap_err();
        assert!(e.contains("f-number"), "{e}");
        let p = pitch::resolve(&facts, f.width, f.height, Some(0.0043));
        assert_eq!(
            (p.pitch_mm, p.source),
            (Some(0.0043), PitchSource::Override)
        );
    }
}
