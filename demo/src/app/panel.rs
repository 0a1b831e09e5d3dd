//! The egui side panel: technique and settings, world, statistics and GPU times.
//!
//! egui's texture updates (the font atlas grows as new glyphs appear) are uploaded as soon
//! as the panel has run, before the frame may be skipped for an outdated surface: a skipped
//! frame must not lose them, or glyphs go missing from then on.

use std::path::PathBuf;

use voxel_render::{BayerSize, GpuContext, Technique, WeightFunction};
use winit::window::Window;

use super::post::FRAME_FORMAT;
use super::{Gfx, PanelFrame, Ui};

/// Where the time-of-day slider starts: mid-morning, close to the default lighting.
const DEFAULT_HOUR: f32 = 10.5;

impl Ui {
    pub(super) fn new(window: &Window, ctx: &GpuContext) -> Self {
        let egui_ctx = egui::Context::default();
        let state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.caps.limits.max_texture_dimension_2d as usize),
        );
        let renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            FRAME_FORMAT,
            egui_wgpu::RendererOptions::default(),
        );
        Self {
            ctx: egui_ctx,
            state,
            renderer,
        }
    }

    /// Frees the textures egui let go of (after the frame that last used them).
    pub(super) fn free(&mut self, ids: &[egui::TextureId]) {
        for id in ids {
            self.renderer.free_texture(id);
        }
    }
}

impl Gfx {
    /// Runs the panel for this frame and uploads its texture updates at once.
    pub(super) fn run_panel(&mut self) -> PanelFrame {
        let raw = self.ui.state.take_egui_input(&self.display.window);
        let egui_ctx = self.ui.ctx.clone();
        let mut panel_right = 0.0;
        let output = egui_ctx.run_ui(raw, |ui| panel_right = self.panel(ui));
        self.ui
            .state
            .handle_platform_output(&self.display.window, output.platform_output);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.ui
                    .renderer
                    .update_texture(&self.ctx.device, &self.ctx.queue, *id, delta);
            }
        }
        let ppp = output.pixels_per_point;
        PanelFrame {
            paint_jobs: egui_ctx.tessellate(output.shapes, ppp),
            free: output.textures_delta.free.iter().copied().collect(),
            pixels_per_point: ppp,
            view_x: (panel_right * ppp).ceil() as u32,
        }
    }

    /// Draws the panel over the frame; returns egui's own command buffers, to be
    /// submitted before the frame's.
    pub(super) fn draw_panel(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        panel: &PanelFrame,
    ) -> Vec<wgpu::CommandBuffer> {
        let frame = &self.frames.frame;
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [frame.texture.width(), frame.texture.height()],
            pixels_per_point: panel.pixels_per_point,
        };
        let extra = self.ui.renderer.update_buffers(
            &self.ctx.device,
            &self.ctx.queue,
            encoder,
            &panel.paint_jobs,
            &screen,
        );
        let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("egui"),
            color_attachments: &[voxel_render::stages::load(&frame.view)],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.ui
            .renderer
            .render(&mut pass.forget_lifetime(), &panel.paint_jobs, &screen);
        extra
    }

    /// Draws the side panel; returns its right edge in points.
    fn panel(&mut self, ui: &mut egui::Ui) -> f32 {
        let response = egui::Panel::left("settings")
            .default_size(250.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("voxel-oit");
                    self.technique_settings(ui);
                    ui.separator();
                    self.world_settings(ui);
                    ui.separator();
                    self.statistics(ui);
                });
            });
        response.response.rect.max.x
    }

    fn technique_settings(&mut self, ui: &mut egui::Ui) {
        let s = &mut self.settings;
        ui.label(format!(
            "Technique (keys 1-9, 0; [ ] step through all {})",
            Technique::ALL.len()
        ));
        egui::ComboBox::from_id_salt("technique")
            .selected_text(s.oit.technique.name())
            .show_ui(ui, |ui| {
                for t in Technique::ALL {
                    ui.selectable_value(&mut s.oit.technique, t, t.name());
                }
            });
        let t = s.oit.technique;
        let wboit = matches!(t, Technique::WboitMrt | Technique::WboitTwoPass);
        ui.add_enabled_ui(wboit, |ui| {
            let w = &mut s.oit.wboit.weight;
            egui::ComboBox::from_label("WBOIT weight")
                .selected_text(w.name())
                .show_ui(ui, |ui| {
                    for option in WeightFunction::ALL {
                        ui.selectable_value(w, option, option.name());
                    }
                });
        });
        ui.add_enabled_ui(t == Technique::Stipple, |ui| {
            let st = &mut s.oit.stipple;
            ui.horizontal(|ui| {
                ui.label("Bayer");
                for b in BayerSize::ALL {
                    ui.selectable_value(&mut st.bayer, b, format!("{0}x{0}", b.side()));
                }
            });
            ui.checkbox(&mut st.depth_write, "stipple writes depth");
        });
        ui.add_enabled_ui(t == Technique::DepthPeeling, |ui| {
            ui.horizontal(|ui| {
                ui.label("Peel layers");
                for n in [4, 6, 8] {
                    ui.selectable_value(&mut s.oit.peeling.layers, n, n.to_string());
                }
            });
        });
        ui.add_enabled_ui(
            matches!(t, Technique::Sorted | Technique::SortedQuads),
            |ui| {
                let mut quads = t == Technique::SortedQuads;
                if ui
                    .checkbox(&mut quads, "sort quads inside chunks")
                    .changed()
                {
                    s.oit.technique = if quads {
                        Technique::SortedQuads
                    } else {
                        Technique::Sorted
                    };
                }
            },
        );
        ui.checkbox(&mut s.msaa, "4x MSAA (opaque and cutout)");
        ui.label("Game content (through the frame stages)");
        ui.horizontal(|ui| {
            ui.checkbox(
                &mut s.game.bubbles,
                format!("{} bubbles", super::game::BUBBLES),
            );
            ui.checkbox(&mut s.game.cube, "glass cube");
            ui.checkbox(&mut s.game.boat, "boat");
        });
        ui.add(egui::Slider::new(&mut s.fade_in_frames, 0..=60).text("fade-in frames"));
        ui.checkbox(&mut s.heatmap, "error map against the reference (H)");
    }

    fn world_settings(&mut self, ui: &mut egui::Ui) {
        let s = &mut self.settings;
        match &self.scene {
            Some(scene) => {
                ui.label(format!("Scene: {}", scene.name));
            }
            None => {
                ui.horizontal(|ui| {
                    ui.label("Seed");
                    ui.add(egui::DragValue::new(&mut s.seed));
                });
            }
        }
        let most = if self.scene.is_some() {
            super::STREAMED_VIEW_DISTANCE
        } else {
            super::MAX_DEMO_VIEW_DISTANCE
        };
        ui.add(
            egui::Slider::new(&mut s.view_distance, 1..=most)
                .logarithmic(true)
                .text("view distance (chunks)"),
        );
        if self.streaming.far.is_some() {
            ui.checkbox(&mut s.level_bands, "levels of detail as bands (L)");
        }
        // The default lighting until the slider is moved; then the sun (or, at night, the
        // moon) of that hour.
        let mut hour = s.hour.unwrap_or(DEFAULT_HOUR);
        let slider = egui::Slider::new(&mut hour, 0.0..=24.0).text("time of day (h)");
        if ui.add(slider).changed() {
            s.hour = Some(hour);
        }
        let registry = self.streaming.streamer.world().registry().clone();
        egui::ComboBox::from_label("block to place")
            .selected_text(registry.get(s.place).map_or("?", |d| d.name.as_str()))
            .show_ui(ui, |ui| {
                for (id, d) in registry.iter().skip(1) {
                    ui.selectable_value(&mut s.place, id, d.name.as_str());
                }
            });
        if ui.button("Screenshot (F2)").clicked() {
            self.script.screenshot_request = Some(PathBuf::from(format!(
                "screenshots/voxel-oit-{}.png",
                self.status.frame_index
            )));
        }
    }

    fn statistics(&mut self, ui: &mut egui::Ui) {
        let st = &self.status.stats;
        ui.label(format!(
            "{:.0} FPS, CPU {:.2} ms",
            self.status.fps, st.cpu_ms
        ));
        ui.label(format!(
            "chunks drawn: {} opaque, {} cutout, {} translucent",
            st.meshes_drawn[0], st.meshes_drawn[1], st.meshes_drawn[2]
        ));
        ui.label(format!("translucent quads: {}", st.translucent_quads));
        let streamer = &self.streaming.streamer;
        let last = &self.streaming.last;
        let memory = self.renderer.chunk_memory();
        ui.label(format!(
            "streaming: {} chunks held ({:.1} MiB), {} on the GPU ({:.1} MiB of quads), {} jobs, {} uploads",
            streamer.world().len(),
            streamer.memory_bytes() as f64 / f64::from(1 << 20),
            voxel_render::low_level::chunks(&self.renderer).len(),
            memory.quad_bytes as f64 / f64::from(1 << 20),
            last.jobs,
            last.uploads
        ));
        if let Some((field, status)) = &self.streaming.far {
            ui.label(format!(
                "far view: {} chunks drawn{}",
                status.drawn_chunks,
                match status.drawn_finest {
                    None => ", the horizon coming".to_owned(),
                    Some(0) if field.is_idle() => String::new(),
                    Some(l) => format!(", level {l} the finest so far, {} to mesh", status.missing),
                }
            ));
            for m in field.memory() {
                let s = voxel_core::level_scale(m.level);
                ui.label(format!(
                    "  level {} ({s}-block cells): {} chunks, {:.1} MiB of quads",
                    m.level,
                    m.chunks,
                    (m.quads * 8) as f64 / f64::from(1 << 20)
                ));
            }
        }
        let report = &st.technique;
        if let Some(sort) = report.sort {
            ui.label(format!(
                "quad sort: {:.3} ms, {} chunks",
                sort.ms, sort.chunks_resorted
            ));
        }
        if let Some(l) = report.peeling.and_then(|p| p.layers) {
            ui.label(format!("layers peeled: {l}"));
        }
        if let Some(r) = report.reference {
            ui.label(format!(
                "reference: {} lost, {} capped pixels",
                r.lost_fragments, r.capped_pixels
            ));
        }
        ui.label("GPU ms per pass:");
        for (pass, ms) in self.status.gpu_times.iter() {
            ui.label(format!("  {pass}: {ms:.3}"));
        }
        ui.separator();
        ui.small("WASD + Space/Shift fly, Ctrl faster; right-drag or arrows look; left click places, right click (or Ctrl+left, Q) removes, E places.");
        if !self.status.message.is_empty() {
            ui.small(&self.status.message);
        }
    }
}
