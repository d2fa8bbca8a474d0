//! The sky as numbers, on the CPU: where the sun is for a time of day, a latitude and a day of
//! the year ([`sun`]), and the light of a clear atmosphere, single scattering of Rayleigh and Mie
//! through a spherical shell ([`scattering`]), tabulated for the renderer as a small sky-view
//! table with the sun's colour, the sky's light and the night's light ([`SkyLight`]).
//!
//! Directions are world directions (y-up); an azimuth is a compass bearing in degrees, 0 toward
//! -z (north in the engine's maps) and 90 toward +x (east).

pub mod scattering;
pub mod sun;

pub use scattering::{Atmosphere, SKY_VIEW_HEIGHT, SKY_VIEW_WIDTH, SkyLight};
pub use sun::{SolarPosition, TimeOfDay, solar_position};
