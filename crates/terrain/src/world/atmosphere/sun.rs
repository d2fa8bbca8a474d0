//! The sun's place in the sky for a time of day, a latitude and a day of the year.
//!
//! The clock is local apparent solar time (12:00 is the sun's highest point, whatever the time
//! zone and the equation of time). The declination follows Spencer's Fourier series (1971),
//! within a few hundredths of a degree of the true one all year; elevation and azimuth are then the standard spherical-astronomy formulas (e.g. Duffie and
//! Beckman, *Solar Engineering of Thermal Processes*, ch. 1.6).

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A time of day, in hours since midnight (0 to below 24), local solar time.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct TimeOfDay(f32);

impl TimeOfDay {
    /// The time `hours` after midnight, wrapped into a day (25.5 is 01:30).
    pub fn from_hours(hours: f32) -> Self {
        let wrapped = hours.rem_euclid(24.0);
        // rem_euclid can round up to 24 itself for tiny negative inputs.
        Self(if wrapped >= 24.0 { 0.0 } else { wrapped })
    }

    /// Hours since midnight, 0 to below 24.
    pub fn hours(self) -> f32 {
        self.0
    }
}

impl fmt::Display for TimeOfDay {
    /// `HH:MM`, rounded to the nearest minute.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let minutes = (self.0 * 60.0).round() as u32 % (24 * 60);
        write!(f, "{:02}:{:02}", minutes / 60, minutes % 60)
    }
}

impl FromStr for TimeOfDay {
    type Err = String;

    /// `HH:MM` or `HH:MM:SS` on a 24-hour clock (`06:30`, `18:05:30`).
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = || format!("`{text}` is not a time of day (expected HH:MM, 00:00 to 23:59)");
        let parts: Vec<&str> = text.trim().split(':').collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(bad());
        }
        let mut values = [0u32; 3];
        for (value, part) in values.iter_mut().zip(&parts) {
            if part.is_empty() || part.len() > 2 || !part.bytes().all(|b| b.is_ascii_digit()) {
                return Err(bad());
            }
            *value = part.parse().map_err(|_| bad())?;
        }
        let [hours, minutes, seconds] = values;
        if hours > 23 || minutes > 59 || seconds > 59 {
            return Err(bad());
        }
        Ok(Self(hours as f32 + minutes as f32 / 60.0 + seconds as f32 / 3600.0))
    }
}

impl Serialize for TimeOfDay {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for TimeOfDay {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let text = String::deserialize(deserializer)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// Where the sun is, in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolarPosition {
    /// Above the horizon (negative below it), -90 to 90.
    pub elevation_degrees: f32,
    /// Compass bearing, 0 north (toward -z), 90 east (toward +x), 0 to below 360.
    pub azimuth_degrees: f32,
}

impl SolarPosition {
    /// Unit vector toward the sun (y-up, north toward -z, east toward +x).
    pub fn direction(&self) -> Vec3 {
        direction(self.elevation_degrees, self.azimuth_degrees)
    }
}

/// Unit vector (y-up) of a direction `elevation_degrees` above the horizon at compass bearing
/// `azimuth_degrees` (0 toward -z, 90 toward +x).
pub fn direction(elevation_degrees: f32, azimuth_degrees: f32) -> Vec3 {
    let (azimuth, elevation) = (azimuth_degrees.to_radians(), elevation_degrees.to_radians());
    Vec3::new(azimuth.sin() * elevation.cos(), elevation.sin(), -azimuth.cos() * elevation.cos())
}

/// The sun's declination in degrees on day `day_of_year` (1 = 1 January; Spencer's series).
pub fn declination_degrees(day_of_year: u32) -> f64 {
    let g = std::f64::consts::TAU * (f64::from(day_of_year) - 1.0) / 365.0;
    let radians = 0.006918 - 0.399912 * g.cos() + 0.070257 * g.sin() - 0.006758 * (2.0 * g).cos()
        + 0.000907 * (2.0 * g).sin()
        - 0.002697 * (3.0 * g).cos()
        + 0.00148 * (3.0 * g).sin();
    radians.to_degrees()
}

/// The sun's place at `time` (local solar time) on day `day_of_year` (1 to 366) seen from
/// `latitude_degrees` (-90 south to 90 north).
pub fn solar_position(time: TimeOfDay, latitude_degrees: f32, day_of_year: u32) -> SolarPosition {
    let declination = declination_degrees(day_of_year).to_radians();
    let latitude = f64::from(latitude_degrees.clamp(-90.0, 90.0)).to_radians();
    // 15 degrees an hour, 0 at solar noon, negative in the morning.
    let hour_angle = (15.0 * (f64::from(time.hours()) - 12.0)).to_radians();
    let sin_elevation =
        latitude.sin() * declination.sin() + latitude.cos() * declination.cos() * hour_angle.cos();
    let elevation = sin_elevation.clamp(-1.0, 1.0).asin();
    // Measured from south, positive toward the west; then from north, clockwise.
    let from_south =
        hour_angle.sin().atan2(hour_angle.cos() * latitude.sin() - declination.tan() * latitude.cos());
    let azimuth = (from_south.to_degrees() + 180.0).rem_euclid(360.0);
    SolarPosition { elevation_degrees: elevation.to_degrees() as f32, azimuth_degrees: azimuth as f32 }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(text: &str) -> TimeOfDay {
        text.parse().expect("a time")
    }

    #[test]
    fn equinox_noon_stands_at_ninety_minus_the_latitude() {
        // 20 March (day 79) and 23 September (day 266).
        for day in [79, 266] {
            for latitude in [-60.0f32, -33.9, 0.0, 23.0, 45.0, 51.5, 70.0] {
                let noon = solar_position(at("12:00"), latitude, day);
                let expected = 90.0 - latitude.abs();
                assert!(
                    (noon.elevation_degrees - expected).abs() < 1.0,
                    "day {day}, latitude {latitude}: {noon:?}"
                );
                // North of the equator the noon sun is due south, south of it due north.
                if latitude > 1.0 {
                    assert!((noon.azimuth_degrees - 180.0).abs() < 0.01, "{noon:?}");
                } else if latitude < -1.0 {
                    assert!(noon.azimuth_degrees < 0.01 || noon.azimuth_degrees > 359.99, "{noon:?}");
                }
            }
        }
    }

    #[test]
    fn solstices_and_known_values() {
        // Declination at the solstices within a degree of +-23.44.
        assert!((declination_degrees(172) - 23.44).abs() < 1.0);
        assert!((declination_degrees(355) + 23.44).abs() < 1.0);
        // Midsummer noon at 45 N: 90 - 45 + 23.44.
        let summer = solar_position(at("12:00"), 45.0, 172);
        assert!((summer.elevation_degrees - 68.44).abs() < 1.0, "{summer:?}");
        // At the equinox the sun rises due east at 06:00 and sets due west at 18:00, anywhere.
        for latitude in [0.0, 40.0, -40.0] {
            let rise = solar_position(at("06:00"), latitude, 80);
            let set = solar_position(at("18:00"), latitude, 80);
            assert!(
                rise.elevation_degrees.abs() < 1.0 && (rise.azimuth_degrees - 90.0).abs() < 2.0,
                "{rise:?}"
            );
            assert!(
                set.elevation_degrees.abs() < 1.0 && (set.azimuth_degrees - 270.0).abs() < 2.0,
                "{set:?}"
            );
        }
        // Midnight at midsummer: below the horizon by 90 - latitude - declination at 45 N.
        let midnight = solar_position(at("00:00"), 45.0, 172);
        assert!((midnight.elevation_degrees + (90.0 - 45.0 - 23.44)).abs() < 1.0, "{midnight:?}");
        // The midnight sun north of the Arctic circle in June.
        assert!(solar_position(at("00:00"), 75.0, 172).elevation_degrees > 0.0);
        // Morning in the east, afternoon in the west.
        assert!(solar_position(at("09:00"), 45.0, 172).azimuth_degrees < 180.0);
        assert!(solar_position(at("15:00"), 45.0, 172).azimuth_degrees > 180.0);
    }

    #[test]
    fn directions_follow_the_compass() {
        let north = direction(0.0, 0.0);
        assert!((north - Vec3::NEG_Z).length() < 1e-6);
        let east = direction(0.0, 90.0);
        assert!((east - Vec3::X).length() < 1e-6);
        assert!((direction(90.0, 123.0) - Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn times_parse_print_and_wrap() {
        assert_eq!(at("06:30").hours(), 6.5);
        assert_eq!(at("18:05:36").to_string(), "18:06");
        assert_eq!(at("00:00").to_string(), "00:00");
        assert_eq!(TimeOfDay::from_hours(25.5).to_string(), "01:30");
        assert_eq!(TimeOfDay::from_hours(-0.25).to_string(), "23:45");
        assert_eq!(TimeOfDay::from_hours(23.999).to_string(), "00:00");
        for bad in ["24:00", "12:60", "12", "12:3x", "", "1:2:3:4", "-1:00", "123:00"] {
            assert!(bad.parse::<TimeOfDay>().is_err(), "{bad}");
        }
    }
}
