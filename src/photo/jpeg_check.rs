//! A structural check of a JPEG's entropy-coded (scan) data, for the
//! corruption the decoder forgives: the `image` crate's JPEG decoder stops at
//! the first damaged spot of a scan, fills the rest of the picture with
//! grey and reports success. This walk (one pass over the bytes, no
//! decoding) finds what such damage leaves in the byte stream: a marker that
//! cannot occur inside or right after a scan, restart markers out of order
//! or fewer than the frame's MCUs need, or a segment running past the end.
//! Damage that leaves a valid-looking bit stream (a flipped bit inside the
//! Huffman data) cannot be seen without decoding and is not caught here.

/// The first sign of damaged scan data in JPEG `bytes`, as a sentence for a
/// warning; `None` for a sound file (or one that is not a JPEG).
pub fn scan_damage(bytes: &[u8]) -> Option<String> {
    if bytes.len() < 4 || bytes[0] != 0xFF || bytes[1] != 0xD8 {
        return None;
    }
    let mut i = 2;
    let mut restart_interval = 0usize;
    let mut mcus: Option<usize> = None;
    let mut progressive = false;
    let mut components = 0usize;
    loop {
        // Next marker: fill bytes (FF) may precede it.
        if i + 1 >= bytes.len() {
            return Some("the data ends before the end-of-image marker".into());
        }
        if bytes[i] != 0xFF {
            return Some(format!(
                "byte {i}: a marker was expected, found 0x{:02X}",
                bytes[i]
            ));
        }
        let mut m = bytes[i + 1];
        while m == 0xFF {
            i += 1;
            if i + 1 >= bytes.len() {
                return Some("the data ends inside a marker".into());
            }
            m = bytes[i + 1];
        }
        match m {
            0xD9 => return None,
            0xD8 | 0x01 | 0xD0..=0xD7 => {
                i += 2;
                continue;
            }
            _ => {}
        }
        if i + 3 >= bytes.len() {
            return Some(format!("byte {i}: segment header cut off"));
        }
        let len = u16::from_be_bytes([bytes[i + 2], bytes[i + 3]]) as usize;
        let body = i + 4;
        let end = i + 2 + len;
        if len < 2 || end > bytes.len() {
            return Some(format!(
                "byte {i}: segment FF{m:02X} of {len} bytes runs past the end of the file"
            ));
        }
        let seg = &bytes[body..end];
        match m {
            0xDD if seg.len() >= 2 => {
                restart_interval = u16::from_be_bytes([seg[0], seg[1]]) as usize;
            }
            0xC0..=0xCF if !matches!(m, 0xC4 | 0xC8 | 0xCC) && seg.len() >= 6 => {
                progressive = matches!(m, 0xC2 | 0xC6 | 0xCA | 0xCE);
                mcus = frame_mcus(seg);
                components = seg[5] as usize;
            }
            _ => {}
        }
        if m != 0xDA {
            i = end;
            continue;
        }
        // Start of scan: walk the entropy-coded data up to the next marker.
        let scan_components = seg.first().copied().unwrap_or(0) as usize;
        let (next, restarts) = match walk_scan(bytes, end) {
            Ok(v) => v,
            Err(msg) => return Some(msg),
        };
        let whole_frame = !progressive && scan_components == components && components > 0;
        if whole_frame
            && restart_interval > 0
            && let Some(n) = mcus
        {
            let expected = n.div_ceil(restart_interval).saturating_sub(1);
            if restarts < expected {
                return Some(format!(
                    "scan data cut short at byte {next}: {restarts} of {expected} restart markers (about {}% of the picture decoded)",
                    100 * (restarts + 1) / (expected + 1)
                ));
            }
        }
        match bytes.get(next + 1) {
            // What may follow a scan: end of image, another scan, tables, comments, APPn.
            Some(0xD9 | 0xDA | 0xC4 | 0xDB | 0xDD | 0xDC | 0xFE | 0xE0..=0xEF) => i = next,
            Some(&x) => {
                return Some(format!(
                    "byte {next}: marker FF{x:02X} inside the scan data (damaged data; the rest of the picture is not decoded)"
                ));
            }
            None => return Some("the scan data runs to the end of the file".into()),
        }
    }
}

/// From the start of entropy-coded data at `start`: the position of the marker
/// that ends the scan, and the number of restart markers passed (which must
/// come in the order RST0…RST7, RST0…).
fn walk_scan(bytes: &[u8], start: usize) -> Result<(usize, usize), String> {
    let mut j = start;
    let mut restarts = 0usize;
    loop {
        let k = match bytes[j..].iter().position(|&b| b == 0xFF) {
            Some(p) => j + p,
            None => return Err("the scan data runs to the end of the file".into()),
        };
        let mut n = k + 1;
        while bytes.get(n) == Some(&0xFF) {
            n += 1;
        }
        match bytes.get(n) {
            Some(0x00) => j = n + 1,
            Some(&r @ 0xD0..=0xD7) => {
                let want = 0xD0 + (restarts % 8) as u8;
                if r != want {
                    return Err(format!(
                        "byte {k}: restart marker RST{} where RST{} was due (damaged scan data)",
                        r - 0xD0,
                        want - 0xD0
                    ));
                }
                restarts += 1;
                j = n + 1;
            }
            Some(_) => return Ok((n - 1, restarts)),
            None => return Err("the scan data runs to the end of the file".into()),
        }
    }
}

/// The number of MCUs of a frame from its SOF segment body.
fn frame_mcus(sof: &[u8]) -> Option<usize> {
    let height = u16::from_be_bytes([sof[1], sof[2]]) as usize;
    let width = u16::from_be_bytes([sof[3], sof[4]]) as usize;
    let nc = sof[5] as usize;
    if nc == 0 || sof.len() < 6 + 3 * nc || width == 0 || height == 0 {
        return None;
    }
    let comps = &sof[6..6 + 3 * nc];
    if nc == 1 {
        // A single-component scan is not interleaved: one 8×8 block per MCU.
        return Some(width.div_ceil(8) * height.div_ceil(8));
    }
    let hmax = comps.chunks(3).map(|c| (c[1] >> 4) as usize).max()?;
    let vmax = comps.chunks(3).map(|c| (c[1] & 15) as usize).max()?;
    if hmax == 0 || vmax == 0 {
        return None;
    }
    Some(width.div_ceil(8 * hmax) * height.div_ceil(8 * vmax))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A JPEG without restart markers (the image crate's encoder), or one
    /// with a restart marker every 43 MCUs (libjpeg-turbo's cjpeg; see
    /// testdata/regenerate.sh).
    fn jpeg(restart: bool) -> Vec<u8> {
        if restart {
            let p = concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/testdata/restart_markers_cjpeg.jpg"
            );
            return std::fs::read(p).unwrap();
        }
        let img = image::RgbImage::from_fn(160, 96, |x, y| {
            image::Rgb([(x * 3) as u8, (y * 5) as u8, ((x ^ y) * 7) as u8])
        });
        let mut out = std::io::Cursor::new(Vec::new());
        image::DynamicImage::ImageRgb8(img)
            .write_to(&mut out, image::ImageFormat::Jpeg)
            .unwrap();
        out.into_inner()
    }

    #[test]
    fn sound_files_pass() {
        assert_eq!(scan_damage(&jpeg(false)), None);
        assert_eq!(scan_damage(&jpeg(true)), None);
        let canon = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/testdata/real/exif_jpeg/canon_powershot_sx60hs_hdr_NO.jpg"
        );
        assert_eq!(scan_damage(&std::fs::read(canon).unwrap()), None);
        assert_eq!(scan_damage(b"\x89PNG"), None);
    }

    #[test]
    fn garbage_in_the_scan_is_found() {
        let mut j = jpeg(false);
        let mid = j.len() / 2;
        // A deterministic pseudo-random block over the middle of the scan.
        let mut x = 0x2545F491u32;
        for b in &mut j[mid..mid + 200] {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            *b = (x >> 24) as u8;
        }
        j[mid + 100] = 0xFF;
        j[mid + 101] = 0xC3;
        let w = scan_damage(&j).expect("damage found");
        assert!(w.contains("marker"), "{w}");
    }

    #[test]
    fn restart_markers_cut_short_or_out_of_order_are_found() {
        let j = jpeg(true);
        // Drop the middle third of the scan, keeping the end-of-image marker.
        let (a, b) = (j.len() / 3, 2 * j.len() / 3);
        let mut cut = j[..a].to_vec();
        cut.extend_from_slice(&j[b..]);
        assert!(scan_damage(&cut).is_some());
        // Swap one RST number.
        let mut k = j.clone();
        let p = k
            .windows(2)
            .position(|w| w == [0xFF, 0xD2])
            .expect("RST2 present");
        k[p + 1] = 0xD5;
        let w = scan_damage(&k).unwrap();
        assert!(w.contains("RST5 where RST2"), "{w}");
    }
}
