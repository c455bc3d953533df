//! A contact sheet: images side by side in a grid, each named under its
//! picture, to compare the renders of a sweep (`rayoflight sheet`) at a
//! glance. The names are drawn with the study chart's embedded font, so
//! the sheet needs no system font and works in the headless build.

use crate::study::chart::register_font;
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

/// Why the sheet could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw the contact sheet: {0}")]
pub struct SheetError(String);

/// The sheet of `images` (name, picture) in reading order, `columns` a
/// row (none: as square a grid as the count allows). Each cell is as
/// large as the largest picture (and at least [`MIN_CELL_WIDTH`] wide, for
/// the name), the picture centred in it.
pub fn contact_sheet(
    images: &[(String, RgbImage)],
    columns: Option<usize>,
) -> Result<RgbImage, SheetError> {
    let count = images.len().max(1);
    let columns = columns
        .unwrap_or_else(|| (count as f64).sqrt().ceil() as usize)
        .clamp(1, count) as u32;
    let rows = count.div_ceil(columns as usize) as u32;
    let cell_w = images
        .iter()
        .map(|(_, i)| i.width())
        .max()
        .unwrap_or(1)
        .max(MIN_CELL_WIDTH);
    let cell_h = images.iter().map(|(_, i)| i.height()).max().unwrap_or(1) + LABEL_HEIGHT;
    let width = columns * (cell_w + GAP) + GAP;
    let height = rows * (cell_h + GAP) + GAP;
    let mut sheet = RgbImage::from_pixel(width, height, BACKGROUND);
    let cell = |k: usize| {
        let (c, r) = (k as u32 % columns, k as u32 / columns);
        (GAP + c * (cell_w + GAP), GAP + r * (cell_h + GAP))
    };
    for (k, (_, picture)) in images.iter().enumerate() {
        let (x, y) = cell(k);
        let (dx, dy) = (
            (cell_w - picture.width()) / 2,
            (cell_h - LABEL_HEIGHT - picture.height()) / 2,
        );
        image::imageops::replace(&mut sheet, picture, i64::from(x + dx), i64::from(y + dy));
    }
    register_font().map_err(|e| SheetError(e.to_string()))?;
    let err = |e: DrawingAreaErrorKind<_>| SheetError(e.to_string());
    {
        let area = BitMapBackend::with_buffer(&mut sheet, (width, height)).into_drawing_area();
        let font = ("sans-serif", 15).into_font();
        let style = font
            .color(&RGBColor(230, 230, 230))
            .pos(Pos::new(HPos::Center, VPos::Center));
        for (k, (name, _)) in images.iter().enumerate() {
            let (x, y) = cell(k);
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
    fn a_long_name_keeps_its_end() {
        let measure = |t: &str| t.chars().count() as u32 * 10;
        assert_eq!(fitting("short", 100, measure), "short");
        assert_eq!(
            fitting("0-object[1].material.ka=0.25", 100, measure),
            "…l.ka=0.25"
        );
    }
}
