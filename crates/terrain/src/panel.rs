//! The tuning panel (egui), toggled in the window with F1: the look, the time of day, the sun,
//! the fog, the water, the ground's materials, the level of detail and wireframe, a graph of the
//! last frames' times, and saving or loading the settings file. It edits a [`Settings`] in place; the window applies the changes.

use std::collections::VecDeque;
use std::path::Path;

use egui::{Color32, RichText};

use crate::settings::{Look, ReflectionQuality, Settings};
use crate::world::atmosphere::{TimeOfDay, solar_position};

/// Frames the frame-time graph shows.
pub const GRAPH_FRAMES: usize = 240;

/// What the user asked the panel for, besides editing the settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PanelRequests {
    /// Save the settings to the file.
    pub save: bool,
    /// Load the settings from the file.
    pub load: bool,
}

/// The panel's own state: the recent frame times and the last message.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    frame_times: VecDeque<f32>,
    message: Option<String>,
}

impl Panel {
    /// Records the time of a frame, in milliseconds.
    pub fn record_frame(&mut self, milliseconds: f32) {
        if self.frame_times.len() == GRAPH_FRAMES {
            self.frame_times.pop_front();
        }
        self.frame_times.push_back(milliseconds);
    }

    /// Shows `message` under the buttons (e.g. where the settings were saved).
    pub fn set_message(&mut self, message: String) {
        self.message = Some(message);
    }

    /// The median and the 95th percentile of the recorded frame times, in milliseconds.
    pub fn frame_time_summary(&self) -> Option<(f32, f32)> {
        let mut times: Vec<f32> = self.frame_times.iter().copied().collect();
        if times.is_empty() {
            return None;
        }
        times.sort_by(f32::total_cmp);
        let at = |fraction: f32| times[((times.len() - 1) as f32 * fraction).round() as usize];
        Some((at(0.5), at(0.95)))
    }

    /// Lays the panel out in `ctx`, editing `settings`. `file` is where Save and Load go;
    /// `wireframe` whether the GPU can draw edges.
    pub fn show(
        &mut self,
        ctx: &egui::Context,
        settings: &mut Settings,
        file: &Path,
        wireframe: bool,
    ) -> PanelRequests {
        let mut requests = PanelRequests::default();
        // A fixed window without a title bar: the look's buttons are the first widgets Tab
        // reaches.
        egui::Window::new("rayterra terrain")
            .title_bar(false)
            .fixed_pos([8.0, 8.0])
            .default_width(290.0)
            .resizable(false)
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    ui.strong("rayterra terrain");
                    ui.label(RichText::new("F1 hides this panel").weak());
                });
                ui.horizontal(|ui| {
                    ui.label("Look");
                    ui.radio_value(&mut settings.look, Look::Modern, "Modern");
                    ui.radio_value(&mut settings.look, Look::Course, "Course");
                });
                self.graph(ui);
                let modern = settings.look == Look::Modern;
                ui.add_enabled_ui(modern, |ui| sky(ui, settings));
                ui.add_enabled_ui(modern, |ui| sun(ui, settings));
                ui.add_enabled_ui(modern, |ui| fog(ui, settings));
                ui.add_enabled_ui(modern, |ui| water(ui, settings));
                ui.add_enabled_ui(modern, |ui| ground(ui, settings));
                egui::CollapsingHeader::new("Terrain").default_open(true).show(ui, |ui| {
                    ui.add(
                        egui::Slider::new(&mut settings.terrain.lod_error_pixels, 0.5..=16.0)
                            .logarithmic(true)
                            .text("LOD error (pixels)"),
                    );
                    ui.add_enabled(
                        wireframe,
                        egui::Checkbox::new(&mut settings.terrain.wireframe, "Wireframe"),
                    )
                    .on_disabled_hover_text("this GPU cannot draw lines");
                });
                ui.separator();
                ui.horizontal(|ui| {
                    requests.save = ui.button("Save").clicked();
                    requests.load = ui.button("Load").clicked();
                    if ui.button("Defaults").clicked() {
                        let look = settings.look;
                        *settings = Settings { look, view: settings.view.clone(), ..Settings::default() };
                    }
                });
                ui.label(RichText::new(file.display().to_string()).small().weak());
                if let Some(message) = &self.message {
                    ui.label(RichText::new(message).small());
                }
            });
        requests
    }

    /// The frame-time graph: the last [`GRAPH_FRAMES`] frames, with their median and 95th
    /// percentile.
    fn graph(&self, ui: &mut egui::Ui) {
        let summary = self.frame_time_summary();
        let text = summary.map_or_else(
            || "frame time: -".to_string(),
            |(median, high)| format!("frame time: median {median:.1} ms, 95% under {high:.1} ms"),
        );
        ui.label(text);
        let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 48.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, Color32::from_black_alpha(90));
        let top = self.frame_times.iter().copied().fold(1.0f32, f32::max) * 1.1;
        let points: Vec<egui::Pos2> = self
            .frame_times
            .iter()
            .enumerate()
            .map(|(i, &ms)| {
                let x = rect.left() + rect.width() * i as f32 / (GRAPH_FRAMES - 1) as f32;
                egui::pos2(x, rect.bottom() - rect.height() * (ms / top))
            })
            .collect();
        painter.add(egui::Shape::line(points, egui::Stroke::new(1.5, Color32::from_rgb(120, 220, 140))));
        // A line at 1/60 s, when it fits.
        if top > 16.7 {
            let y = rect.bottom() - rect.height() * (16.7 / top);
            painter.hline(rect.x_range(), y, egui::Stroke::new(1.0, Color32::from_white_alpha(40)));
        }
    }
}

/// A colour button. The colour is written back only when the user changes it: showing the button
/// converts it back and forth, which could change its last bits.
fn colour(ui: &mut egui::Ui, rgb: &mut [f32; 3]) {
    ui.horizontal(|ui| {
        let mut edited = *rgb;
        if ui.color_edit_button_rgb(&mut edited).changed() {
            *rgb = edited;
        }
        ui.label("colour");
    });
}

/// The time of day and the place. The time is written back only when the user moves it (a
/// running day moves it too, between frames).
fn sky(ui: &mut egui::Ui, settings: &mut Settings) {
    egui::CollapsingHeader::new("Time of day").default_open(true).show(ui, |ui| {
        let sky = &mut settings.sky;
        let mut timed = sky.time_of_day.is_some();
        if ui.checkbox(&mut timed, "Sun from the time of day").changed() {
            sky.time_of_day = timed.then(|| TimeOfDay::from_hours(12.0));
        }
        ui.add_enabled_ui(timed, |ui| {
            let mut hours = sky.time_of_day.map_or(12.0, TimeOfDay::hours);
            let slider = egui::Slider::new(&mut hours, 0.0..=23.99)
                .text("time")
                .custom_formatter(|hours, _| TimeOfDay::from_hours(hours as f32).to_string());
            if ui.add(slider).changed() {
                sky.time_of_day = Some(TimeOfDay::from_hours(hours));
            }
            ui.add(egui::Slider::new(&mut sky.latitude_degrees, -90.0..=90.0).text("latitude (°)"));
            ui.add(egui::Slider::new(&mut sky.day_of_year, 1..=366).text("day of the year"));
            ui.horizontal(|ui| {
                ui.checkbox(&mut sky.day_runs, "Day runs (T)");
                ui.add(
                    egui::Slider::new(&mut sky.day_hours_per_second, 0.01..=24.0)
                        .logarithmic(true)
                        .text("h/s"),
                );
            });
            if let Some(time) = sky.time_of_day {
                let sun = solar_position(time, sky.latitude_degrees, sky.day_of_year);
                ui.label(
                    RichText::new(format!(
                        "sun {:.1}° up, azimuth {:.0}°",
                        sun.elevation_degrees, sun.azimuth_degrees
                    ))
                    .small()
                    .weak(),
                );
            }
        });
    });
}

fn sun(ui: &mut egui::Ui, settings: &mut Settings) {
    let timed = settings.sky.time_of_day.is_some();
    egui::CollapsingHeader::new("Sun").default_open(true).show(ui, |ui| {
        let sun = &mut settings.sun;
        ui.horizontal(|ui| {
            ui.checkbox(&mut sun.lighting, "Lighting");
            ui.checkbox(&mut sun.shadows, "Shadows");
        });
        ui.add_enabled(
            !timed,
            egui::Slider::new(&mut sun.elevation_degrees, -10.0..=90.0).text("elevation (°)"),
        );
        ui.add_enabled(!timed, egui::Slider::new(&mut sun.azimuth_degrees, 0.0..=360.0).text("azimuth (°)"));
        colour(ui, &mut sun.colour);
        ui.add(egui::Slider::new(&mut sun.intensity, 0.0..=4.0).text("exposure"));
        ui.add(egui::Slider::new(&mut sun.ambient, 0.0..=2.0).text("sky light"));
    });
}

fn fog(ui: &mut egui::Ui, settings: &mut Settings) {
    egui::CollapsingHeader::new("Fog").default_open(true).show(ui, |ui| {
        let fog = &mut settings.fog;
        ui.checkbox(&mut fog.enabled, "Fog");
        ui.add(egui::Slider::new(&mut fog.density, 0.0..=0.3).logarithmic(true).text("density"));
        ui.add(egui::Slider::new(&mut fog.height_falloff, 0.0..=5.0).text("height falloff"));
    });
}

fn ground(ui: &mut egui::Ui, settings: &mut Settings) {
    egui::CollapsingHeader::new("Ground").default_open(false).show(ui, |ui| {
        let ground = &mut settings.ground;
        ui.checkbox(&mut ground.materials, "Materials from the land's shape");
        ui.add_enabled_ui(ground.materials, |ui| {
            ui.add(egui::Slider::new(&mut ground.rock_slope_degrees, 10.0..=80.0).text("rock slope (°)"));
            ui.add(egui::Slider::new(&mut ground.snow_line, 0.0..=1.5).text("snow line"));
            ui.add(egui::Slider::new(&mut ground.sand_line, 0.0..=0.5).text("sand line"));
            ui.add(egui::Slider::new(&mut ground.detail, 0.0..=2.0).text("detail"));
            ui.add(
                egui::Slider::new(&mut ground.texture_size, 0.002..=0.5)
                    .logarithmic(true)
                    .text("texture size"),
            );
        });
    });
}

fn water(ui: &mut egui::Ui, settings: &mut Settings) {
    egui::CollapsingHeader::new("Water").default_open(true).show(ui, |ui| {
        let water = &mut settings.water;
        colour(ui, &mut water.colour);
        ui.add(egui::Slider::new(&mut water.clarity, 0.01..=10.0).logarithmic(true).text("clarity"));
        ui.add(egui::Slider::new(&mut water.wave_speed, 0.0..=10.0).text("wave speed"));
        ui.add(egui::Slider::new(&mut water.wave_scale, 0.1..=20.0).logarithmic(true).text("wave scale"));
        ui.add(egui::Slider::new(&mut water.wave_strength, 0.0..=2.0).text("wave strength"));
        egui::ComboBox::from_label("reflection").selected_text(water.reflection.name()).show_ui(ui, |ui| {
            for quality in ReflectionQuality::ALL {
                ui.selectable_value(&mut water.reflection, quality, quality.name());
            }
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut water.refraction, "Sea floor");
            ui.checkbox(&mut water.glint, "Glint");
            ui.checkbox(&mut water.foam, "Foam");
        });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_times_keep_the_last_frames() {
        let mut panel = Panel::default();
        assert_eq!(panel.frame_time_summary(), None);
        for i in 0..(GRAPH_FRAMES + 60) {
            panel.record_frame(i as f32);
        }
        assert_eq!(panel.frame_times.len(), GRAPH_FRAMES);
        let (median, high) = panel.frame_time_summary().expect("frames recorded");
        assert_eq!(median, 180.0);
        assert_eq!(high, 287.0);
    }

    #[test]
    fn the_panel_lays_out_and_edits_settings() {
        // One frame of the panel with no input: it lays out without changing anything.
        let ctx = egui::Context::default();
        let mut panel = Panel::default();
        panel.record_frame(20.0);
        let mut settings = Settings::default();
        let before = settings.clone();
        let mut requests = PanelRequests::default();
        let output = ctx.run_pass(egui::RawInput::default(), |ctx| {
            requests = panel.show(ctx, &mut settings, Path::new("s.toml"), true);
        });
        // Something was laid out (the fonts' texture is set up).
        assert!(!output.shapes.is_empty());
        output.drop_without_applying_deltas();
        assert_eq!(settings, before);
        assert_eq!(requests, PanelRequests::default());
        // With a time of day (its slider and the sun's place) too.
        settings.sky.time_of_day = Some(TimeOfDay::from_hours(18.75));
        let before = settings.clone();
        let output = ctx.run_pass(egui::RawInput::default(), |ctx| {
            requests = panel.show(ctx, &mut settings, Path::new("s.toml"), true);
        });
        output.drop_without_applying_deltas();
        assert_eq!(settings, before);
    }
}
