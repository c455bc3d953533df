//! A rectangle of the full image's pixels: what `--region` renders, what
//! a part covers, what `split` hands to each task.
//!
//! Regions are half-open, `X0,Y0,X1,Y1` with `X0 ≤ x < X1`, `Y0 ≤ y < Y1`,
//! in the pixels of the full image (0, 0 at its top left), as POV-Ray's
//! `+SC/+EC/+SR/+ER` and pbrt's `--pixelbounds` name them.

use std::fmt;

/// A non-empty rectangle of pixels, half-open.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// Why a region cannot be read or used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RegionError {
    #[error("expects X0,Y0,X1,Y1: four pixel numbers, such as 0,0,320,240")]
    Syntax,
    #[error("{0} is empty: X1 must be above X0 and Y1 above Y0")]
    Empty(Region),
    #[error("{region} is outside the {width}×{height} image")]
    Outside {
        region: Region,
        width: u32,
        height: u32,
    },
}

impl Region {
    /// The whole of a `width × height` image.
    pub fn whole(width: u32, height: u32) -> Region {
        Region {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// A region, if it holds at least one pixel.
    pub fn new(x0: u32, y0: u32, x1: u32, y1: u32) -> Result<Region, RegionError> {
        let region = Region { x0, y0, x1, y1 };
        if x1 > x0 && y1 > y0 {
            Ok(region)
        } else {
            Err(RegionError::Empty(region))
        }
    }

    /// Reads `X0,Y0,X1,Y1` (spaces around the numbers allowed).
    pub fn parse(text: &str) -> Result<Region, RegionError> {
        let numbers: Vec<u32> = text
            .split(',')
            .map(|n| n.trim().parse().map_err(|_| RegionError::Syntax))
            .collect::<Result<_, _>>()?;
        match numbers[..] {
            [x0, y0, x1, y1] => Region::new(x0, y0, x1, y1),
            _ => Err(RegionError::Syntax),
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels in the region.
    pub fn area(&self) -> u64 {
        u64::from(self.width()) * u64::from(self.height())
    }

    /// Checks that the region lies in a `width × height` image.
    pub fn check_in(self, width: u32, height: u32) -> Result<Region, RegionError> {
        if self.x1 <= width && self.y1 <= height {
            Ok(self)
        } else {
            Err(RegionError::Outside {
                region: self,
                width,
                height,
            })
        }
    }

    /// The pixels both regions hold, if any.
    pub fn intersection(&self, other: &Region) -> Option<Region> {
        Region::new(
            self.x0.max(other.x0),
            self.y0.max(other.y0),
            self.x1.min(other.x1),
            self.y1.min(other.y1),
        )
        .ok()
    }

    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

impl fmt::Display for Region {
    /// `X0,Y0,X1,Y1`, as [`Region::parse`] reads it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_read_back_as_written() {
        let r = Region::parse("3, 4,10,20").unwrap();
        assert_eq!(r, Region::new(3, 4, 10, 20).unwrap());
        assert_eq!(Region::parse(&r.to_string()), Ok(r));
        assert_eq!((r.width(), r.height(), r.area()), (7, 16, 112));
        for bad in ["", "1,2,3", "1,2,3,4,5", "a,0,1,1", "-1,0,1,1", "0;0;1;1"] {
            assert_eq!(Region::parse(bad), Err(RegionError::Syntax), "{bad:?}");
        }
        assert!(matches!(
            Region::parse("5,0,5,9"),
            Err(RegionError::Empty(_))
        ));
        assert_eq!(r.check_in(10, 20), Ok(r));
        assert!(r.check_in(9, 20).is_err() && r.check_in(10, 19).is_err());
        assert_eq!(
            r.check_in(9, 20).unwrap_err().to_string(),
            "3,4,10,20 is outside the 9×20 image"
        );
    }

    #[test]
    fn intersections_hold_the_shared_pixels() {
        let a = Region::new(0, 0, 10, 10).unwrap();
        let b = Region::new(5, 8, 20, 30).unwrap();
        assert_eq!(a.intersection(&b), Some(Region::new(5, 8, 10, 10).unwrap()));
        let c = Region::new(10, 0, 12, 10).unwrap();
        assert_eq!(a.intersection(&c), None, "touching is not overlapping");
        assert!(a.contains(9, 0) && !a.contains(10, 0));
    }
}
