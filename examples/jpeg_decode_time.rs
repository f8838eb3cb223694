//! Wall time of the luma-only JPEG decode, with zune-jpeg's IDCT inline and
//! on a second thread (vendor/zune-jpeg/SWEEPMTF.md), interleaved; and of
//! `photo::jpeg::decode_jpeg` (which also pre-faults the output's pages).
//!
//! ```sh
//! cargo run --release --features examples --example jpeg_decode_time -- FILE.jpg [PAIRS]
//! ```

use std::time::Instant;
use zune_core::bytestream::ZCursor;
use zune_core::colorspace::ColorSpace;
use zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

fn zune(bytes: &[u8], pipelined: bool, out: &mut [u8]) -> f64 {
    let t = Instant::now();
    let opts = DecoderOptions::default()
        .set_max_width(usize::MAX)
        .set_max_height(usize::MAX)
        .jpeg_set_out_colorspace(ColorSpace::Luma);
    let mut d = JpegDecoder::new_with_options(ZCursor::new(bytes), opts);
    d.set_pipelined_idct(Some(pipelined));
    d.decode_into(out).expect("decodes");
    t.elapsed().as_secs_f64() * 1e3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: jpeg_decode_time FILE.jpg [PAIRS]");
    let pairs: usize = args.get(2).map_or(21, |s| s.parse().expect("a count"));
    let bytes = std::fs::read(path).expect("read");
    let mut d = JpegDecoder::new(ZCursor::new(&bytes));
    d.decode_headers().expect("headers");
    let (w, h) = d.dimensions().expect("dimensions");
    let mut a = vec![0u8; w * h];
    let mut b = vec![0u8; w * h];
    let want = sweepmtf::photo::jpeg::JpegWant {
        rows: None,
        luma_only: true,
    };
    // `only inline|pipelined`: that one alone (for `perf` or CPU time).
    if let Some(mode) = args.get(3) {
        let t: Vec<f64> = (0..pairs)
            .map(|_| zune(&bytes, mode == "pipelined", &mut a))
            .collect();
        println!("{mode}: {:.1} ms", median(t));
        return;
    }
    let (mut inline, mut piped, mut ours) = (vec![], vec![], vec![]);
    for _ in 0..pairs {
        inline.push(zune(&bytes, false, &mut a));
        piped.push(zune(&bytes, true, &mut b));
        let t = Instant::now();
        let dec = sweepmtf::photo::jpeg::decode_jpeg(&bytes, path, want).expect("decodes");
        ours.push(t.elapsed().as_secs_f64() * 1e3);
        drop(dec);
    }
    assert!(a == b, "the two decodes differ");
    let ratios: Vec<f64> = piped.iter().zip(&inline).map(|(p, i)| p / i).collect();
    println!(
        "{w}×{h}: inline {:.1} ms, pipelined {:.1} ms (median ratio {:.2}), decode_jpeg {:.1} ms; {pairs} pairs",
        median(inline),
        median(piped),
        median(ratios),
        median(ours)
    );
}
