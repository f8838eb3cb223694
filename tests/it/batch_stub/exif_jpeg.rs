//! Inserts a minimal EXIF block (Make, Model, ExposureTime, FNumber, ISO,
//! FocalLength, LensModel) into JPEG bytes, as a camera would write it, so
//! simulated shots carry the facts that real photos carry.

#![allow(dead_code)]

/// Camera facts to write.
#[derive(Debug, Clone, Default)]
pub struct Facts {
    pub make: String,
    pub model: String,
    pub lens: String,
    /// (numerator, denominator)
    pub f_number: (u32, u32),
    pub focal_length: (u32, u32),
    pub exposure_time: (u32, u32),
    pub iso: u16,
    /// Sensor pixel pitch in µm (written as FocalPlaneX/YResolution in
    /// pixels per cm) and the image size it describes; `None` = not written.
    pub pitch_um_and_size: Option<(f64, u32, u32)>,
}

struct Entry {
    tag: u16,
    typ: u16,
    count: u32,
    data: Vec<u8>,
}

fn ascii(tag: u16, s: &str) -> Entry {
    let mut data = s.as_bytes().to_vec();
    data.push(0);
    Entry {
        tag,
        typ: 2,
        count: data.len() as u32,
        data,
    }
}

fn rational(tag: u16, (n, d): (u32, u32)) -> Entry {
    let mut data = n.to_be_bytes().to_vec();
    data.extend(d.to_be_bytes());
    Entry {
        tag,
        typ: 5,
        count: 1,
        data,
    }
}

/// One IFD starting at TIFF offset `start`, its out-of-line values after it.
fn ifd(mut entries: Vec<Entry>, start: u32) -> Vec<u8> {
    entries.sort_by_key(|e| e.tag);
    let n = entries.len() as u32;
    let mut data_off = start + 2 + 12 * n + 4;
    let mut head = (n as u16).to_be_bytes().to_vec();
    let mut tail = Vec::new();
    for e in &entries {
        head.extend(e.tag.to_be_bytes());
        head.extend(e.typ.to_be_bytes());
        head.extend(e.count.to_be_bytes());
        if e.data.len() <= 4 {
            let mut v = e.data.clone();
            v.resize(4, 0);
            head.extend(v);
        } else {
            head.extend(data_off.to_be_bytes());
            tail.extend(&e.data);
            if tail.len() % 2 == 1 {
                tail.push(0);
            }
            data_off = start + 2 + 12 * n + 4 + tail.len() as u32;
        }
    }
    head.extend(0u32.to_be_bytes()); // no next IFD
    head.extend(tail);
    head
}

/// `jpeg` with an APP1 EXIF segment holding `f` inserted after the SOI marker.
pub fn with_exif(jpeg: &[u8], f: &Facts) -> Vec<u8> {
    assert_eq!(&jpeg[..2], &[0xFF, 0xD8], "not a JPEG");
    let ifd0_entries = |exif_at: u32| {
        vec![
            ascii(0x010F, &f.make),
            ascii(0x0110, &f.model),
            Entry {
                tag: 0x8769,
                typ: 4,
                count: 1,
                data: exif_at.to_be_bytes().to_vec(),
            },
        ]
    };
    let ifd0_len = ifd(ifd0_entries(0), 8).len() as u32;
    let exif_at = 8 + ifd0_len;
    let mut tiff = b"MM\0\x2A".to_vec();
    tiff.extend(8u32.to_be_bytes());
    tiff.extend(ifd(ifd0_entries(exif_at), 8));
    let mut exif_entries = vec![
        rational(0x829A, f.exposure_time),
        rational(0x829D, f.f_number),
        Entry {
            tag: 0x8827,
            typ: 3,
            count: 1,
            data: f.iso.to_be_bytes().to_vec(),
        },
        rational(0x920A, f.focal_length),
        ascii(0xA434, &f.lens),
    ];
    if let Some((pitch_um, w, h)) = f.pitch_um_and_size {
        let long = |tag: u16, v: u32| Entry {
            tag,
            typ: 4,
            count: 1,
            data: v.to_be_bytes().to_vec(),
        };
        // Pixels per cm = 1e4 / pitch_um, as a rational with denominator 1000.
        let res = ((1e7 / pitch_um).round() as u32, 1000);
        exif_entries.push(long(0xA002, w));
        exif_entries.push(long(0xA003, h));
        exif_entries.push(rational(0xA20E, res));
        exif_entries.push(rational(0xA20F, res));
        exif_entries.push(Entry {
            tag: 0xA210,
            typ: 3,
            count: 1,
            data: 3u16.to_be_bytes().to_vec(), // centimetres
        });
    }
    tiff.extend(ifd(exif_entries, exif_at));
    let mut app1 = b"Exif\0\0".to_vec();
    app1.extend(tiff);
    let len = (app1.len() + 2) as u16;
    let mut out = jpeg[..2].to_vec();
    out.extend([0xFF, 0xE1]);
    out.extend(len.to_be_bytes());
    out.extend(app1);
    out.extend(&jpeg[2..]);
    out
}
