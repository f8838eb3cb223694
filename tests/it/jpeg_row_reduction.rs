//! The search image summed from a pipelined JPEG decode's rows as they are
//! written (`locate::row_reduction`, on the decoder's second thread) is the
//! image the search makes itself from the decoded photo, to the bit; it is
//! taken only when complete and made with the search's own table, and a
//! damaged file never leaves a wrong one.

use super::jpeg_pipelined_idct::{damaged, encode};
use jpeg_encoder::SamplingFactor;
use std::borrow::Cow;
use sweepmtf::locate::Source;
use sweepmtf::locate::row_reduction::{ReducedSearch, SharedReduction};
use sweepmtf::photo::decode::{Decoded, decode_bytes_observed};
use sweepmtf::photo::jpeg::JpegWant;
use sweepmtf::photo::linearise::{Channel, Tone, default_tone};

/// The luma decode with a row reduction watching (as `measure` makes it),
/// on a pool of two threads (the IDCT thread is used only there).
fn observed(bytes: &[u8]) -> Option<(Decoded, Option<ReducedSearch>)> {
    let shared = SharedReduction::default();
    let lut = default_tone(8).0.lut(256);
    let make = |w: usize, h: usize| shared.observer(w, h, &lut);
    let want = JpegWant {
        rows: None,
        luma_only: true,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let dec = pool
        .install(|| decode_bytes_observed(bytes, "test.jpg", want, Some(&make)))
        .ok()?;
    // As `measure`: a decode with warnings may be a lenient retry, unseen.
    let red = shared.finish().filter(|_| dec.warnings.is_empty());
    Some((dec, red))
}

/// Whether `red`, when given, is the search's own reduced image of `dec`,
/// and whether it was taken.
fn agrees(dec: &Decoded, red: Option<&ReducedSearch>, what: &str) -> bool {
    let own = sweepmtf::locate::of_decoded(dec, &Tone::Srgb, Channel::Luma);
    let plain = own.reduced();
    let with = sweepmtf::locate::of_decoded(dec, &Tone::Srgb, Channel::Luma).with_reduced(red);
    let g = with.reduced();
    assert_eq!(
        (g.w, g.h, g.scale, g.origin),
        (plain.w, plain.h, plain.scale, plain.origin),
        "{what}"
    );
    assert!(
        g.data
            .iter()
            .zip(plain.data.iter())
            .all(|(a, b)| a.to_bits() == b.to_bits()),
        "{what}: the summed search image differs"
    );
    matches!(g.data, Cow::Borrowed(_)) && red.is_some()
}

#[test]
fn search_image_summed_while_decoding_is_the_search_own() {
    // Reduced 2, 3 and 2 times (the search's factor), rows and columns left over.
    let files = [
        (
            "2601×1301 4:2:0",
            encode(2601, 1301, false, SamplingFactor::F_2_2, 92, 0, false),
        ),
        (
            "1951×1933 4:4:4 restarts",
            encode(1951, 1933, false, SamplingFactor::F_1_1, 80, 7, false),
        ),
        (
            "1300×2700 grey",
            encode(1300, 2700, true, SamplingFactor::F_1_1, 95, 0, false),
        ),
    ];
    for (what, b) in &files {
        let (dec, red) = observed(b).expect("decodes");
        assert!(
            agrees(&dec, red.as_ref(), what),
            "{what}: not summed while decoding"
        );
        // Made through another table: left aside, the search reduces itself.
        let other = sweepmtf::locate::of_decoded(&dec, &Tone::Gamma(2.2), Channel::Luma)
            .with_reduced(red.as_ref());
        assert!(
            matches!(other.reduced().data, Cow::Owned(_)),
            "{what}: another table"
        );
        // Damaged files: either no image, or the right one.
        for (how, c) in damaged(b) {
            if let Some((dec, red)) = observed(&c) {
                agrees(&dec, red.as_ref(), &format!("{what} {how}"));
            }
        }
        // Progressive files are never pipelined: nothing summed.
        let (pw, ph) = (dec.width, dec.height);
        let p = encode(pw, ph, false, SamplingFactor::F_2_2, 90, 0, true);
        let (_, red) = observed(&p).expect("decodes");
        assert!(red.is_none(), "{what}: progressive");
    }
}
