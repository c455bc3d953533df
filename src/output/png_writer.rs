//! PNG files, written with every core. Every PNG the project writes goes
//! through [`write_png`]: a render saved whole, a part, the image
//! `assemble` puts together from parts (the same bytes as the whole
//! render's), the study's chart.
//!
//! The image is cut into bands of rows whose height depends on its width
//! alone ([`band_rows`]), so that the file's bytes do not depend on the
//! machine, the thread count, or whether the rows came from one render or
//! from parts. Each band is filtered (each row with the one of PNG's five
//! filters whose output has the smallest sum of absolute values, as
//! libpng chooses) and deflated on its own, on the rayon pool's threads,
//! ending on a byte boundary (a sync flush); the bands' deflate data,
//! joined, is the one zlib stream of the IDAT chunks, its Adler-32
//! combined from the bands' own; each band is an IDAT chunk. An image in
//! memory is compressed straight from its pixels ([`write_png_image`]);
//! rows that arrive a band at a time ([`write_png`]: `assemble`) need
//! never be in memory whole: a few bands a thread are held at once, and
//! the next of them are filled while the last are compressed. Both give
//! the same file. Each thread keeps what compressing a band needs from
//! one band to the next ([`Scratch`]).

use std::io::{self, Write};

/// The raw bytes a band of rows holds, about (a band has at least one
/// row): small enough that a 1080-line image makes a few dozen bands for
/// the threads to share, large enough that restarting the compressor's
/// window at each band costs little (about 1 % of the file).
const BAND_BYTES: usize = 256 * 1024;

/// Bands compressed together, per thread: the rows held in memory while
/// writing are about `BAND_BYTES × BANDS_A_THREAD × threads`, twice, at
/// most `BAND_BYTES × MOST_BANDS` twice. The threads wait for each other
/// once a batch: at 4 bands a thread, `assemble` of 16 parts of a
/// 6000×4500 image was 1.53× faster on 2 cores than on one, at 8 1.67×,
/// at 16 no faster than at 8 (the first batch, read before any is
/// compressed, longer).
const BANDS_A_THREAD: usize = 8;
const MOST_BANDS: usize = 64;

/// The deflate level: zlib's 2 (zlib-rs), as fast as the png crate's
/// "fast" mode and its files about 15 % smaller on renders.
const LEVEL: u32 = 2;

/// The rows of a band of an image `width` pixels wide (8-bit RGB).
pub fn band_rows(width: u32) -> usize {
    let row = 1 + width as usize * 3;
    (BAND_BYTES / row).max(1)
}

/// Writes a `width × height` PNG (8-bit RGB) into `w` a band of rows at a
/// time, top to bottom: `fill` fills each band in turn (a whole number of
/// rows, width × 3 bytes each, [`band_rows`] of them but for the last).
/// `texts` (keyword, text) go in Latin-1 tEXt chunks before the pixels.
/// The same file, byte for byte, as [`write_png_image`] of those rows.
///
/// Everything runs on the rayon pool: the next batch of bands is filled
/// while the pool's other threads compress the batch before (a `join`),
/// so that a `fill` that runs parallel work of its own (`assemble`
/// decoding its parts) shares the threads with the compression instead
/// of taking turns with it, and no thread waits for another to hand it
/// rows.
pub fn write_png<W: Write>(
    w: W,
    width: u32,
    height: u32,
    texts: &[(&str, &str)],
    mut fill: impl FnMut(&mut [u8]) -> io::Result<()> + Send,
) -> io::Result<()> {
    use rayon::prelude::*;
    let mut idat = Idat::new(w, width, height, texts)?;
    let row_bytes = width as usize * 3;
    let rows_a_band = band_rows(width);
    let bands = (height as usize).div_ceil(rows_a_band);
    let batch = (rayon::current_num_threads() * BANDS_A_THREAD).clamp(1, MOST_BANDS);
    let band_bytes =
        |band: usize| rows_a_band.min(height as usize - band * rows_a_band) * row_bytes;
    // The bands from `first` on, a batch of them, into `pixels` (its
    // buffers kept from one batch to the batch after next).
    let read = |first: usize,
                pixels: &mut Vec<Vec<u8>>,
                fill: &mut dyn FnMut(&mut [u8]) -> io::Result<()>| {
        pixels.resize_with(batch.min(bands - first), Vec::new);
        for (k, band) in pixels.iter_mut().enumerate() {
            band.resize(band_bytes(first + k), 0);
            fill(band)?;
        }
        io::Result::Ok(())
    };
    // The row above the current batch's first band (PNG's row above the
    // image is zeros).
    let mut above = vec![0u8; row_bytes];
    let (mut current, mut next) = (Vec::new(), Vec::new());
    if bands > 0 {
        read(0, &mut current, &mut fill)?;
    }
    let mut first = 0;
    while first < bands {
        let after = first + current.len();
        let (read_next, compressed) = rayon::join(
            || match after < bands {
                true => read(after, &mut next, &mut fill),
                false => {
                    next.clear();
                    Ok(())
                }
            },
            || {
                current
                    .par_iter()
                    .enumerate()
                    .map(|(k, pixels)| {
                        let above = match k {
                            0 => &above[..],
                            _ => &current[k - 1][current[k - 1].len() - row_bytes..],
                        };
                        compress_band(above, pixels, row_bytes, first + k + 1 == bands)
                    })
                    .collect::<io::Result<Vec<Band>>>()
            },
        );
        for band in compressed? {
            idat.put(band)?;
        }
        read_next?;
        if let Some(last) = current.last() {
            above.copy_from_slice(&last[last.len() - row_bytes..]);
        }
        first = after;
        std::mem::swap(&mut current, &mut next);
    }
    idat.finish()
}

/// Writes `pixels` (8-bit RGB, `width × height`, row-major) as a PNG into
/// `w`: every band compressed at once, straight from the pixels. The same
/// file, byte for byte, as [`write_png`] of the same rows.
pub fn write_png_image<W: Write>(
    w: W,
    width: u32,
    height: u32,
    pixels: &[u8],
    texts: &[(&str, &str)],
) -> io::Result<()> {
    use rayon::prelude::*;
    let row_bytes = width as usize * 3;
    debug_assert_eq!(pixels.len(), row_bytes * height as usize);
    let mut idat = Idat::new(w, width, height, texts)?;
    let band_bytes = band_rows(width) * row_bytes;
    let zeros = vec![0u8; row_bytes];
    let bands: Vec<&[u8]> = pixels.chunks(band_bytes).collect();
    let compressed = bands
        .par_iter()
        .enumerate()
        .map(|(k, band)| {
            let above = match k {
                0 => &zeros[..],
                _ => &pixels[k * band_bytes - row_bytes..k * band_bytes],
            };
            compress_band(above, band, row_bytes, k + 1 == bands.len())
        })
        .collect::<io::Result<Vec<Band>>>()?;
    for band in compressed {
        idat.put(band)?;
    }
    idat.finish()
}

/// The file being written: its header and texts written, then an IDAT
/// chunk a band, the zlib stream's header before the first band's data
/// and its Adler-32 after the last's.
struct Idat<W: Write> {
    writer: png::Writer<W>,
    adler: u32,
    first: bool,
}

impl<W: Write> Idat<W> {
    fn new(w: W, width: u32, height: u32, texts: &[(&str, &str)]) -> io::Result<Idat<W>> {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        for (keyword, text) in texts {
            encoder
                .add_text_chunk((*keyword).to_owned(), (*text).to_owned())
                .map_err(io::Error::other)?;
        }
        Ok(Idat {
            writer: encoder.write_header().map_err(io::Error::other)?,
            adler: 1,
            first: true,
        })
    }

    /// The next band's chunk.
    fn put(&mut self, band: Band) -> io::Result<()> {
        let mut data = Vec::with_capacity(band.deflated.len() + 6);
        if std::mem::take(&mut self.first) {
            // Deflate, a 32 KiB window, no dictionary, a fast level.
            data.extend_from_slice(&[0x78, 0x5e]);
        }
        data.extend_from_slice(&band.deflated);
        self.adler = adler32_combine(self.adler, band.adler, band.filtered_len);
        if band.last {
            data.extend_from_slice(&self.adler.to_be_bytes());
        }
        self.writer
            .write_chunk(png::chunk::IDAT, &data)
            .map_err(io::Error::other)
    }

    fn finish(self) -> io::Result<()> {
        self.writer.finish().map_err(io::Error::other)
    }
}

/// A band, filtered and deflated.
struct Band {
    /// Raw deflate data, ending on a byte boundary (or the stream's end).
    deflated: Vec<u8>,
    /// Adler-32 of the filtered bytes, and how many there are.
    adler: u32,
    filtered_len: usize,
    /// The image's last band: its data ends the stream.
    last: bool,
}

/// What compressing a band needs besides its pixels, kept by each thread
/// from one band to the next: the filtered bytes, the five trial rows and
/// the compressor's state (about 600 KB in all). Made afresh for each band,
/// their pages were the allocator's to give back and the kernel's to
/// zero again at the next: on a 6000×4500 image, 18 000 page faults,
/// as many as the image's own.
struct Scratch {
    filtered: Vec<u8>,
    trial: [Vec<u8>; 5],
    compress: flate2::Compress,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Option<Scratch>> = const { std::cell::RefCell::new(None) };
}

/// Filters and deflates the rows of `pixels` (`above`: the row above the
/// first); `last`: the stream ends with this band.
fn compress_band(above: &[u8], pixels: &[u8], row_bytes: usize, last: bool) -> io::Result<Band> {
    SCRATCH.with_borrow_mut(|scratch| {
        let scratch = scratch.get_or_insert_with(|| Scratch {
            filtered: Vec::new(),
            trial: Default::default(),
            compress: flate2::Compress::new(flate2::Compression::new(LEVEL), false),
        });
        compress_band_with(scratch, above, pixels, row_bytes, last)
    })
}

fn compress_band_with(
    scratch: &mut Scratch,
    above: &[u8],
    pixels: &[u8],
    row_bytes: usize,
    last: bool,
) -> io::Result<Band> {
    let Scratch {
        filtered,
        trial,
        compress,
    } = scratch;
    filtered.clear();
    filtered.reserve(pixels.len() + pixels.len() / row_bytes);
    for row in trial.iter_mut() {
        row.resize(row_bytes, 0);
    }
    let mut prev = above;
    for row in pixels.chunks_exact(row_bytes) {
        let kind = filter_row(prev, row, trial);
        filtered.push(kind as u8);
        filtered.extend_from_slice(&trial[kind]);
        prev = row;
    }
    // Each band is a deflate stream of its own, from an empty window.
    compress.reset();
    let mut deflated = Vec::with_capacity(filtered.len() / 2 + 64);
    let flush = match last {
        true => flate2::FlushCompress::Finish,
        false => flate2::FlushCompress::Sync,
    };
    loop {
        let at = compress.total_in() as usize;
        if deflated.len() == deflated.capacity() {
            deflated.reserve(deflated.capacity().max(1024));
        }
        let status = compress
            .compress_vec(&filtered[at..], &mut deflated, flush)
            .map_err(io::Error::other)?;
        let done =
            compress.total_in() as usize == filtered.len() && deflated.len() < deflated.capacity();
        if status == flate2::Status::StreamEnd || (!last && done) {
            break;
        }
    }
    Ok(Band {
        adler: simd_adler32::adler32(&filtered.as_slice()),
        filtered_len: filtered.len(),
        deflated,
        last,
    })
}

/// Filters `row` (3 bytes a pixel) with each of PNG's five filters into
/// `trial`, and gives the one whose bytes, read as signed, have the
/// smallest sum of absolute values (the first of equals). Each filter is
/// its own loop without a branch, over slices of one length, which the
/// compiler turns into vector code: this is most of a PNG's time.
fn filter_row(above: &[u8], row: &[u8], trial: &mut [Vec<u8>; 5]) -> usize {
    const BPP: usize = 3;
    let n = row.len();
    let first = BPP.min(n);
    let [none, sub, up, average, paeth] = trial;
    none.copy_from_slice(row);
    // The first pixel: its left and upper left are zeros.
    for i in 0..first {
        sub[i] = row[i];
        up[i] = row[i].wrapping_sub(above[i]);
        average[i] = row[i].wrapping_sub(above[i] / 2);
        paeth[i] = row[i].wrapping_sub(above[i]);
    }
    // The rest: x, its left a, above b and upper left c.
    let len = n - first;
    let x = &row[first..];
    let a = &row[..len];
    let b = &above[first..];
    let c = &above[..len];
    let (sub, up) = (&mut sub[first..], &mut up[first..]);
    let (average, paeth) = (&mut average[first..], &mut paeth[first..]);
    for i in 0..len {
        sub[i] = x[i].wrapping_sub(a[i]);
    }
    for i in 0..len {
        up[i] = x[i].wrapping_sub(b[i]);
    }
    for i in 0..len {
        average[i] = x[i].wrapping_sub(((u16::from(a[i]) + u16::from(b[i])) / 2) as u8);
    }
    for i in 0..len {
        paeth[i] = x[i].wrapping_sub(paeth_predictor(a[i], b[i], c[i]));
    }
    // |b as i8| is the smaller of b and −b (128 for 128): a byte-wise
    // minimum and a sum the compiler vectorizes (no row's sum nears
    // u32::MAX: 128 a byte).
    let cost = |bytes: &[u8]| -> u32 {
        bytes
            .iter()
            .map(|&b| u32::from(b.min(b.wrapping_neg())))
            .sum()
    };
    let costs = trial.each_ref().map(|t| cost(t));
    (0..5).min_by_key(|&k| costs[k]).unwrap_or(0)
}

/// PNG's Paeth predictor: of left, above and upper left, the one nearest
/// to left + above − upper left.
#[inline(always)]
fn paeth_predictor(a: u8, b: u8, c: u8) -> u8 {
    let (ia, ib, ic) = (i16::from(a), i16::from(b), i16::from(c));
    // p − a, p − b and p − c, for p = a + b − c.
    let (pa, pb, pc) = ((ib - ic).abs(), (ia - ic).abs(), (ia + ib - 2 * ic).abs());
    let b_or_c = if pb <= pc { b } else { c };
    if pa <= pb && pa <= pc { a } else { b_or_c }
}

/// The Adler-32 of two byte strings joined, from each one's and the
/// second's length (zlib's `adler32_combine`).
fn adler32_combine(first: u32, second: u32, second_len: usize) -> u32 {
    const BASE: u64 = 65521;
    let rem = second_len as u64 % BASE;
    let mut sum1 = u64::from(first & 0xffff);
    let mut sum2 = (rem * sum1) % BASE;
    sum1 += u64::from(second & 0xffff) + BASE - 1;
    sum2 += u64::from(first >> 16) + u64::from(second >> 16) + BASE - rem;
    if sum1 >= BASE {
        sum1 -= BASE;
    }
    if sum1 >= BASE {
        sum1 -= BASE;
    }
    if sum2 >= 2 * BASE {
        sum2 -= 2 * BASE;
    }
    if sum2 >= BASE {
        sum2 -= BASE;
    }
    (sum1 | (sum2 << 16)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A picture with smooth gradients, edges and noise, `width × height`.
    fn picture(width: u32, height: u32) -> image::RgbImage {
        let mut seed = 12345u32;
        image::RgbImage::from_fn(width, height, |x, y| {
            seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12345);
            let noise = (seed >> 24) as u8 & 7;
            let edge = if (x / 17 + y / 13) % 2 == 0 { 60 } else { 0 };
            image::Rgb([
                (x as u8).wrapping_add(noise),
                (y as u8).wrapping_add(edge),
                ((x + y) as u8) ^ noise,
            ])
        })
    }

    fn written(image: &image::RgbImage, threads: usize) -> Vec<u8> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut file = Vec::new();
        let mut rows = image.as_raw().chunks_exact(image.width() as usize * 3);
        pool.install(|| {
            write_png(
                &mut file,
                image.width(),
                image.height(),
                &[("k", "v")],
                |band| {
                    for row in band.chunks_exact_mut(image.width() as usize * 3) {
                        row.copy_from_slice(rows.next().unwrap());
                    }
                    Ok(())
                },
            )
        })
        .unwrap();
        file
    }

    /// What is written reads back as the same pixels, through the png
    /// crate (which checks the Adler-32 and the chunks' CRCs), at sizes of
    /// one band, several, a band and a row, and one row.
    #[test]
    fn a_written_png_reads_back_as_its_pixels() {
        let bands = band_rows(300) as u32;
        for (width, height) in [
            (1, 1),
            (300, 7),
            (300, bands * 5 + 1),
            (97, 1000),
            (5000, 3),
        ] {
            let image = picture(width, height);
            let file = written(&image, 3);
            let mut decoder = png::Decoder::new(std::io::Cursor::new(&file));
            decoder.ignore_checksums(false);
            let mut reader = decoder.read_info().unwrap();
            let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
            reader.next_frame(&mut pixels).unwrap();
            assert_eq!(pixels, image.as_raw().as_slice(), "{width}×{height}");
            let text = &reader.info().uncompressed_latin1_text;
            assert_eq!(
                (text[0].keyword.as_str(), text[0].text.as_str()),
                ("k", "v")
            );
        }
    }

    /// The file's bytes do not depend on the thread count (however many
    /// batches the bands make), nor on whether the rows came one at a time
    /// or as an image.
    #[test]
    fn the_bytes_are_the_same_on_any_thread_count() {
        let image = picture(700, 3000);
        // Several batches on one and on two threads.
        assert!(3000 / band_rows(700) > 2 * BANDS_A_THREAD);
        let one = written(&image, 1);
        for threads in [2, 3, 8, 17] {
            assert!(written(&image, threads) == one, "{threads} threads");
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut whole = Vec::new();
            pool.install(|| write_png_image(&mut whole, 700, 3000, image.as_raw(), &[("k", "v")]))
                .unwrap();
            assert!(whole == one, "the image on {threads} threads");
        }
    }

    #[test]
    fn adler32_combines_as_computed_whole() {
        let data: Vec<u8> = (0..200_000u32).map(|i| (i * 7 + i / 300) as u8).collect();
        for cut in [0, 1, 65520, 65521, 100_000, 200_000] {
            let (a, b) = data.split_at(cut);
            let whole = simd_adler32::adler32(&data.as_slice());
            let joined = adler32_combine(
                simd_adler32::adler32(&a),
                simd_adler32::adler32(&b),
                b.len(),
            );
            assert_eq!(joined, whole, "cut at {cut}");
        }
    }

    /// The filter chosen is the cheapest, and each filter undoes as PNG
    /// decodes it.
    #[test]
    fn the_filters_are_pngs() {
        let above: Vec<u8> = (0..30).map(|i| (i * 37) as u8).collect();
        let row: Vec<u8> = (0..30).map(|i| (i * 11 + 5) as u8).collect();
        let mut trial = [(); 5].map(|_| vec![0u8; 30]);
        let kind = filter_row(&above, &row, &mut trial);
        let cost = |t: &[u8]| {
            t.iter()
                .map(|&b| (b as i8).unsigned_abs() as u32)
                .sum::<u32>()
        };
        assert!((0..5).all(|k| cost(&trial[kind]) <= cost(&trial[k])));
        for (k, filtered) in trial.iter().enumerate() {
            let mut back = vec![0u8; 30];
            for i in 0..30 {
                let a = if i >= 3 { back[i - 3] } else { 0 };
                let (b, c) = (above[i], if i >= 3 { above[i - 3] } else { 0 });
                let predicted = match k {
                    0 => 0,
                    1 => a,
                    2 => b,
                    3 => ((u16::from(a) + u16::from(b)) / 2) as u8,
                    _ => paeth_predictor(a, b, c),
                };
                back[i] = filtered[i].wrapping_add(predicted);
            }
            assert_eq!(back, row, "filter {k}");
        }
    }
}
