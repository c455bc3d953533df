//! A contact sheet: images side by side in a grid, each named under its
//! picture, to compare the renders of a sweep (`rayoflight sheet`) at a
//! glance. The names are drawn with the embedded font
//! ([`crate::output::font`]), so
//! the sheet needs no system font and works in the headless build.

use image::{Rgb, RgbImage};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Pixels between cells and around the sheet.
pub const GAP: u32 = 8;

/// Height of the line under each picture that holds its name.
pub const LABEL_HEIGHT: u32 = 22;

/// The narrowest cell: room for a name's last dozen characters under a
/// small picture.
pub const MIN_CELL_WIDTH: u32 = 120;

const BACKGROUND: Rgb<u8> = Rgb([48, 48, 48]);

/// Most pixels a sheet may have: 2^30, 3.2 GB as 8-bit RGB. A 16384²
/// render (the largest square a scene may ask for,
/// [`MAX_PIXELS`](crate::scene::MAX_PIXELS)) fits, and one more of its size
/// beside it; a sweep of 600×600 renders, 2700 of them.
pub const MAX_SHEET_PIXELS: u64 = 1 << 30;

/// Why the sheet could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum SheetError {
    #[error("cannot draw the contact sheet: {0}")]
    Draw(String),
    #[error(
        "cannot draw the contact sheet: {count} image{} in {columns} column{} of {cell_width}×{cell_height}-pixel cells make a {width}×{height} sheet ({} pixels), more than the limit of {MAX_SHEET_PIXELS} (2^30)",
        plural(*count),
        plural(*columns as usize),
        u128::from(*width) * u128::from(*height)
    )]
    TooLarge {
        count: usize,
        columns: u64,
        cell_width: u64,
        cell_height: u64,
        width: u64,
        height: u64,
    },
    #[error("cannot draw the {width}×{height} contact sheet: it {source}")]
    Memory {
        width: u32,
        height: u32,
        source: crate::system::resources::NotEnoughMemory,
    },
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Where the pictures go: the grid of a sheet of pictures of some sizes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    pub columns: u32,
    pub rows: u32,
    /// Each cell: as large as the largest picture (and at least
    /// [`MIN_CELL_WIDTH`] wide), and the line for its name.
    pub cell_width: u32,
    pub cell_height: u32,
    /// The whole sheet.
    pub width: u32,
    pub height: u32,
}

impl Layout {
    /// The grid of pictures of `sizes` (width, height) in reading order,
    /// `columns` a row (none: as square a grid as the count allows);
    /// refused, before anything is allocated, where the sheet would have
    /// more than [`MAX_SHEET_PIXELS`].
    pub fn new(sizes: &[(u32, u32)], columns: Option<usize>) -> Result<Layout, SheetError> {
        let count = sizes.len().max(1);
        let columns = columns
            .unwrap_or_else(|| (count as f64).sqrt().ceil() as usize)
            .clamp(1, count) as u64;
        let rows = count.div_ceil(columns as usize) as u64;
        let gap = u64::from(GAP);
        let cell_width =
            u64::from(sizes.iter().map(|s| s.0).max().unwrap_or(1)).max(u64::from(MIN_CELL_WIDTH));
        let cell_height =
            u64::from(sizes.iter().map(|s| s.1).max().unwrap_or(1)) + u64::from(LABEL_HEIGHT);
        let width = columns * (cell_width + gap) + gap;
        let height = rows * (cell_height + gap) + gap;
        if u128::from(width) * u128::from(height) > u128::from(MAX_SHEET_PIXELS) {
            return Err(SheetError::TooLarge {
                count: sizes.len(),
                columns,
                cell_width,
                cell_height,
                width,
                height,
            });
        }
        // Below 2^30 pixels, every side and product fits in a u32.
        let small = |v: u64| u32::try_from(v).expect("a side of a sheet under the limit");
        Ok(Layout {
            columns: small(columns),
            rows: small(rows),
            cell_width: small(cell_width),
            cell_height: small(cell_height),
            width: small(width),
            height: small(height),
        })
    }

    /// Bytes of the sheet as 8-bit RGB.
    pub fn bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 3
    }

    /// The top-left corner of cell `k`.
    fn cell(&self, k: usize) -> (u32, u32) {
        let (c, r) = (k as u32 % self.columns, k as u32 / self.columns);
        (
            GAP + c * (self.cell_width + GAP),
            GAP + r * (self.cell_height + GAP),
        )
    }
}

/// The sheet of `images` (name, picture) in reading order, `columns` a
/// row (none: as square a grid as the count allows). Each cell is as
/// large as the largest picture (and at least [`MIN_CELL_WIDTH`] wide, for
/// the name), the picture centred in it.
pub fn contact_sheet(
    images: &[(String, RgbImage)],
    columns: Option<usize>,
) -> Result<RgbImage, SheetError> {
    let sizes: Vec<(u32, u32)> = images.iter().map(|(_, i)| i.dimensions()).collect();
    let names: Vec<&str> = images.iter().map(|(n, _)| n.as_str()).collect();
    let layout = Layout::new(&sizes, columns)?;
    draw(&layout, &names, |k| {
        Ok::<_, SheetError>(std::borrow::Cow::Borrowed(&images[k].1))
    })
}

/// The sheet of `layout` ([`Layout::new`] of the pictures' sizes) with
/// `names[k]` under picture `k`, each picture asked of `picture` in turn
/// and dropped once placed: the sheet and one picture are in memory, never
/// all of them. The sheet's buffer is taken, not assumed: a size the
/// system cannot give is an error, not an abort.
pub fn draw<'a, E: From<SheetError>>(
    layout: &Layout,
    names: &[&str],
    mut picture: impl FnMut(usize) -> Result<std::borrow::Cow<'a, RgbImage>, E>,
) -> Result<RgbImage, E> {
    let (width, height) = (layout.width, layout.height);
    let mut raw =
        crate::system::resources::buffer::<u8>(layout.bytes() as usize).map_err(|source| {
            SheetError::Memory {
                width,
                height,
                source,
            }
        })?;
    for pixel in raw.chunks_exact_mut(3) {
        pixel.copy_from_slice(&BACKGROUND.0);
    }
    let mut sheet = RgbImage::from_raw(width, height, raw).expect("3 bytes a pixel");
    let (cell_w, cell_h) = (layout.cell_width, layout.cell_height);
    for k in 0..names.len() {
        let picture = picture(k)?;
        let (x, y) = layout.cell(k);
        let (dx, dy) = (
            cell_w.saturating_sub(picture.width()) / 2,
            (cell_h - LABEL_HEIGHT).saturating_sub(picture.height()) / 2,
        );
        image::imageops::replace(&mut sheet, &*picture, i64::from(x + dx), i64::from(y + dy));
    }
    crate::output::font::register().map_err(|e| SheetError::Draw(e.to_string()))?;
    let err = |e: DrawingAreaErrorKind<_>| SheetError::Draw(e.to_string());
    {
        let area = BitMapBackend::with_buffer(&mut sheet, (width, height)).into_drawing_area();
        let font = ("sans-serif", 15).into_font();
        let style = font
            .color(&RGBColor(230, 230, 230))
            .pos(Pos::new(HPos::Center, VPos::Center));
        for (k, name) in names.iter().enumerate() {
            let (x, y) = layout.cell(k);
            let label = fitting(name, cell_w, |text| {
                area.estimate_text_size(text, &style)
                    .map_or(u32::MAX, |(w, _)| w)
            });
            let centre = (
                (x + cell_w / 2) as i32,
                (y + cell_h - LABEL_HEIGHT / 2) as i32,
            );
            area.draw(&Text::new(label, centre, style.clone()))
                .map_err(err)?;
        }
        area.present().map_err(err)?;
    }
    Ok(sheet)
}

/// `name`, or its end after an ellipsis, as much of it as fits `width`
/// pixels by `measure` (the end of a file name says the most: the value).
fn fitting(name: &str, width: u32, measure: impl Fn(&str) -> u32) -> String {
    if measure(name) <= width {
        return name.to_owned();
    }
    let chars: Vec<char> = name.chars().collect();
    (1..chars.len())
        .map(|skip| format!("…{}", chars[skip..].iter().collect::<String>()))
        .find(|text| measure(text) <= width)
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pictures_sit_in_a_grid_with_their_names_under_them() {
        let red = RgbImage::from_pixel(160, 30, Rgb([255, 0, 0]));
        let blue = RgbImage::from_pixel(100, 30, Rgb([0, 0, 255]));
        let images = vec![
            ("a".to_owned(), red.clone()),
            ("b".to_owned(), blue),
            ("c".to_owned(), red),
        ];
        let sheet = contact_sheet(&images, None).unwrap();
        // Two columns (the square root of 3, up), two rows.
        let (cell_w, cell_h) = (160 + GAP, 30 + LABEL_HEIGHT);
        assert_eq!(
            sheet.dimensions(),
            (2 * cell_w + GAP, 2 * (cell_h + GAP) + GAP)
        );
        assert_eq!(sheet.get_pixel(GAP, GAP), &Rgb([255, 0, 0]));
        // The narrower picture is centred in its cell.
        assert_eq!(sheet.get_pixel(GAP + cell_w + 30, GAP), &Rgb([0, 0, 255]));
        assert_eq!(sheet.get_pixel(GAP + cell_w + 29, GAP), &BACKGROUND);
        // Each name is drawn: light pixels in the label line.
        let label_row = GAP + 30 + LABEL_HEIGHT / 2;
        let lit = (GAP..GAP + 160).any(|x| sheet.get_pixel(x, label_row)[0] > 150);
        assert!(lit, "a name under the first picture");
        let one_row = contact_sheet(&images, Some(5)).unwrap();
        assert_eq!(one_row.height(), cell_h + 2 * GAP);
        // Tiny pictures still leave room for their names.
        let dots = vec![("ka=0.25".to_owned(), RgbImage::new(1, 1))];
        let sheet = contact_sheet(&dots, None).unwrap();
        assert_eq!(sheet.width(), MIN_CELL_WIDTH + 2 * GAP);
        let label_row = GAP + 1 + LABEL_HEIGHT / 2;
        assert!((GAP..GAP + MIN_CELL_WIDTH).any(|x| sheet.get_pixel(x, label_row)[0] > 150));
    }

    #[test]
    fn a_sheet_over_the_limit_is_refused_before_it_is_drawn() {
        // 5000 renders of 600×600: 43176×44738 pixels.
        let sizes = vec![(600, 600); 5000];
        let e = Layout::new(&sizes, None).unwrap_err().to_string();
        assert_eq!(
            e,
            "cannot draw the contact sheet: 5000 images in 71 columns of 600×622-pixel \
             cells make a 43176×44738 sheet (1931607888 pixels), more than the limit of \
             1073741824 (2^30)"
        );
        // The largest square render fits, and one more of its size.
        let side = 1 << 14;
        let two = Layout::new(&[(side, side); 2], None).unwrap();
        assert_eq!((two.columns, two.rows), (2, 1));
        assert!(two.bytes() <= 3 * MAX_SHEET_PIXELS);
        assert!(Layout::new(&[(side, side); 3], None).is_err());
        assert!(Layout::new(&vec![(600, 600); 2700], None).is_ok());
        // Sides past u32 are counted, not wrapped.
        let wide = Layout::new(&[(u32::MAX, 1); 3], Some(3)).unwrap_err();
        assert!(matches!(wide, SheetError::TooLarge { .. }), "{wide}");
    }

    #[test]
    fn a_long_name_keeps_its_end() {
        let measure = |t: &str| t.chars().count() as u32 * 10;
        assert_eq!(fitting("short", 100, measure), "short");
        assert_eq!(
            fitting("0-object[1].material.ka=0.25", 100, measure),
            "…l.ka=0.25"
        );
    }
}
