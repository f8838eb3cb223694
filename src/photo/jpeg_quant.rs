//! A JPEG's luma quantisation table, read from its headers (DQT and frame
//! header), and the IJG quality it corresponds to.

/// Zigzag position → natural (row-major) index of an 8×8 block.
const ZIGZAG: [usize; 64] = [
    0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5, 12, 19, 26, 33, 40, 48, 41, 34, 27, 20,
    13, 6, 7, 14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51, 58, 59,
    52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63,
];

/// The IJG (libjpeg) standard luma table at quality 50, natural order (ITU-T T.81 Annex K).
const IJG_LUMA: [u16; 64] = [
    16, 11, 10, 16, 24, 40, 51, 61, 12, 12, 14, 19, 26, 58, 60, 55, 14, 13, 16, 24, 40, 57, 69, 56,
    14, 17, 22, 29, 51, 87, 80, 62, 18, 22, 37, 56, 68, 109, 103, 77, 24, 35, 55, 64, 81, 104, 113,
    92, 49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99,
];

/// The quantisation table (natural order, DCT units) of the first
/// component of the first frame (luma in YCbCr and grey JPEGs); None when the
/// headers do not give one before the first scan.
pub fn luma_table(b: &[u8]) -> Option<[u16; 64]> {
    let mut tables: [Option<[u16; 64]>; 4] = [None; 4];
    let mut first_component_table: Option<usize> = None;
    for (m, _, seg) in super::jpeg::header_segments(b) {
        if m == 0xDB {
            let mut k = 0;
            while k < seg.len() {
                let (pq, tq) = ((seg[k] >> 4) as usize, (seg[k] & 0x0F) as usize);
                k += 1;
                let mut t = [0u16; 64];
                for z in ZIGZAG {
                    t[z] = if pq == 0 {
                        *seg.get(k)? as u16
                    } else {
                        u16::from_be_bytes([*seg.get(k)?, *seg.get(k + 1)?])
                    };
                    k += 1 + pq.min(1);
                }
                *tables.get_mut(tq)? = Some(t);
            }
        } else if super::jpeg::is_frame_header(m) {
            first_component_table = Some(*seg.get(8)? as usize & 0x0F);
        } else if m == 0xDA {
            return *tables.get(first_component_table?)?;
        }
    }
    None
}

/// The IJG quality (1–100) whose scaled standard luma table is nearest to
/// `table` (median of the entry ratios; 100 for a table of ones).
pub fn ijg_quality(table: &[u16; 64]) -> f64 {
    let mut r: Vec<f64> = table
        .iter()
        .zip(IJG_LUMA)
        .map(|(&q, s)| q as f64 / s as f64)
        .collect();
    r.sort_by(f64::total_cmp);
    // IJG: scale = 5000/q below 50, 200 − 2q from 50; table = std · scale / 100.
    let scale = 100.0 * 0.5 * (r[31] + r[32]);
    let q = if scale <= 100.0 {
        (200.0 - scale) / 2.0
    } else {
        5000.0 / scale
    };
    q.clamp(1.0, 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tables written by another encoder (the image crate's, which scales the
    /// IJG tables as libjpeg does): read back in natural order, quality recovered.
    #[test]
    fn reads_the_table_an_encoder_wrote_and_its_quality() {
        for q in [50u8, 75, 92] {
            let img =
                image::GrayImage::from_fn(16, 16, |x, y| image::Luma([(x * 13 + y * 7) as u8]));
            let mut buf = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, q)
                .encode_image(&img)
                .unwrap();
            let t = luma_table(&buf).expect("a table");
            let scale = if q < 50 {
                5000 / q as u32
            } else {
                200 - 2 * q as u32
            };
            let want: Vec<u16> = IJG_LUMA
                .iter()
                .map(|&s| ((s as u32 * scale + 50) / 100).clamp(1, 255) as u16)
                .collect();
            assert_eq!(t.to_vec(), want, "q{q}");
            assert!(
                (ijg_quality(&t) - q as f64).abs() <= 1.0,
                "{}",
                ijg_quality(&t)
            );
        }
    }

    #[test]
    fn truncated_or_foreign_headers_give_none() {
        assert_eq!(luma_table(b""), None);
        assert_eq!(luma_table(&[0xFF, 0xD8, 0xFF, 0xDB, 0x00]), None);
        assert_eq!(luma_table(b"\x89PNG\r\n\x1a\n"), None);
    }
}
