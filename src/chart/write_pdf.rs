//! PDF writer: one page of exactly the chart's physical size (MediaBox in
//! points, 72 per inch) showing the 16-bit grey raster at its DPI.
//!
//! The page, catalog and content objects come from `pdf-writer`; the image
//! XObject is streamed by hand (Flate with the PNG Up predictor, so rows
//! that repeat their predecessor compress to almost nothing) and the
//! cross-reference table is written from the byte offsets counted on the way.

use super::preview::PreviewBuilder;
use super::raster::Renderer;
use flate2::{Compression, write::ZlibEncoder};
use pdf_writer::{Chunk, Content, Name, Rect, Ref};
use std::io::{self, Write};

/// The largest page side PDF viewers accept (200 inches, in mm).
pub const MAX_PAGE_MM: f64 = 5080.0;

/// Points (1/72 inch) in a millimetre.
pub const PT_PER_MM: f64 = 72.0 / 25.4;

struct Counting<W: Write> {
    inner: W,
    pos: u64,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.pos += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Streams the chart into `out` as a one-page PDF of `width_mm`×`height_mm`.
pub fn write<W: Write>(
    r: &Renderer<'_>,
    dpi: u32,
    width_mm: f64,
    height_mm: f64,
    out: W,
    preview: &mut PreviewBuilder,
) -> io::Result<()> {
    let mut w = Counting { inner: out, pos: 0 };
    let mut offsets: Vec<u64> = Vec::new();
    w.write_all(b"%PDF-1.5\n%\xE2\xE3\xCF\xD3\n")?;
    let (catalog, pages, page, content, image, length) = (
        Ref::new(1),
        Ref::new(2),
        Ref::new(3),
        Ref::new(4),
        Ref::new(5),
        Ref::new(6),
    );
    let page_w = (width_mm * PT_PER_MM) as f32;
    let page_h = (height_mm * PT_PER_MM) as f32;
    // The raster at its DPI: (pixels / dpi) inches.
    let img_w = (r.width as f64 / dpi as f64 * 72.0) as f32;
    let img_h = (r.height as f64 / dpi as f64 * 72.0) as f32;
    let mut objs: Vec<Chunk> = Vec::new();
    let mut c = Chunk::new();
    c.indirect(catalog)
        .start::<pdf_writer::writers::Catalog>()
        .pages(pages);
    objs.push(c);
    let mut c = Chunk::new();
    c.pages(pages).kids([page]).count(1);
    objs.push(c);
    let mut c = Chunk::new();
    {
        let mut p = c.page(page);
        p.parent(pages)
            .media_box(Rect::new(0.0, 0.0, page_w, page_h))
            .contents(content);
        p.resources().x_objects().pair(Name(b"Im0"), image);
    }
    objs.push(c);
    let mut ops = Content::new();
    ops.save_state()
        // Top-left of the raster at the page's top-left corner.
        .transform([img_w, 0.0, 0.0, img_h, 0.0, page_h - img_h])
        .x_object(Name(b"Im0"))
        .restore_state();
    let ops = ops.finish();
    let mut c = Chunk::new();
    c.stream(content, &ops);
    objs.push(c);
    for c in &objs {
        offsets.push(w.pos);
        w.write_all(c.as_bytes())?;
    }
    // Image XObject, streamed.
    offsets.push(w.pos);
    write!(
        w,
        "5 0 obj\n<< /Type /XObject /Subtype /Image /Width {wd} /Height {ht} \
         /ColorSpace /DeviceGray /BitsPerComponent 16 /Filter /FlateDecode \
         /DecodeParms << /Predictor 12 /Colors 1 /BitsPerComponent 16 /Columns {wd} >> \
         /Length 6 0 R >>\nstream\n",
        wd = r.width,
        ht = r.height
    )?;
    let start = w.pos;
    let mut z = ZlibEncoder::new(&mut w, Compression::fast());
    let mut prev = vec![0u8; r.width * 2];
    let mut cur = vec![0u8; r.width * 2 + 1];
    r.stream(|_, row| {
        preview.push(row);
        cur[0] = 2; // PNG "Up" predictor
        for ((d, p), v) in cur[1..]
            .chunks_exact_mut(2)
            .zip(prev.chunks_exact_mut(2))
            .zip(row)
        {
            let b = v.to_be_bytes();
            d[0] = b[0].wrapping_sub(p[0]);
            d[1] = b[1].wrapping_sub(p[1]);
            p.copy_from_slice(&b);
        }
        z.write_all(&cur)
    })?;
    z.finish()?;
    let len = w.pos - start;
    w.write_all(b"\nendstream\nendobj\n")?;
    offsets.push(w.pos);
    let _ = length;
    write!(w, "6 0 obj\n{len}\nendobj\n")?;
    let xref = w.pos;
    write!(w, "xref\n0 {}\n0000000000 65535 f \n", offsets.len() + 1)?;
    for o in &offsets {
        writeln!(w, "{o:010} 00000 n ")?;
    }
    write!(
        w,
        "trailer\n<< /Size {} /Root 1 0 R >>\nstartxref\n{xref}\n%%EOF\n",
        offsets.len() + 1
    )?;
    w.flush()
}
