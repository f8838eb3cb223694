//! Time to render and encode whole charts (criterion): an A3 log-sweep chart
//! with three contrast rows at 1200 dpi (19843 × 14031 px) streamed into a
//! discarding sink as PNG and as PDF, and the same chart's rows rendered
//! without encoding. Wall-clock time; on a busy machine it includes waiting
//! for a core. The peak-memory bar is checked with a documented release run
//! (`/usr/bin/time -v`, see README "Printing charts").

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::io::{Seek, SeekFrom, Write};
use sweepmtf::chart::{self, ChartSpec, Encoding, Format, Law, raster::Renderer};

/// Counts bytes and forgets them; seeking only moves the position.
struct Sink {
    pos: u64,
    len: u64,
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.pos += buf.len() as u64;
        self.len = self.len.max(self.pos);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for Sink {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.pos = match to {
            SeekFrom::Start(p) => p,
            SeekFrom::End(d) => (self.len as i64 + d) as u64,
            SeekFrom::Current(d) => (self.pos as i64 + d) as u64,
        };
        Ok(self.pos)
    }
}

fn a3_1200() -> chart::Chart {
    let mut s = ChartSpec::new(Law::Log, 0.1, 10.0);
    s.width_mm = 420.0;
    s.height_mm = 297.0;
    s.dpi = 1200;
    s.contrasts = vec![0.8, 0.4, 0.2];
    chart::layout(&s).expect("valid chart")
}

fn bench(c: &mut Criterion) {
    let chart = a3_1200();
    let enc = Encoding::Srgb;
    let mut g = c.benchmark_group("chart_a3_1200dpi");
    g.sample_size(10);
    for (name, format) in [("png", Format::Png), ("pdf", Format::Pdf)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut sink = Sink { pos: 0, len: 0 };
                chart::write_chart(&chart, &enc, format, &mut sink, "sink").unwrap();
                black_box(sink.len)
            })
        });
    }
    g.bench_function("render_rows_only", |b| {
        let r = Renderer::new(&chart, &enc);
        b.iter(|| {
            let mut acc = 0u64;
            r.stream(|_, row| {
                acc += row[row.len() / 2] as u64;
                Ok::<(), ()>(())
            })
            .unwrap();
            black_box(acc)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
