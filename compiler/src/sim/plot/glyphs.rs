//! Text for the bitmap: a drawing backend that wraps another (the PNG's
//! [`plotters::prelude::BitMapBackend`]) and lays out and rasterizes text
//! itself with `ab_glyph` and the embedded font ([`super::font`]), with each
//! glyph's side bearing and kerning, a baseline that honours the anchor, and
//! rotation (the y-axis labels). Everything else goes to the inner backend.
//! On wasm32 (the playground) the SVG backend is wrapped too, for the
//! measures only ([`Typeset::measuring`]): plotters has no font there.

use ab_glyph::{point, Font, FontRef, GlyphId, PxScaleFont, ScaleFont};
use plotters_backend::{
    text_anchor::{HPos, VPos},
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
    FontStyle,
};

/// A backend whose text is typeset with the embedded font.
pub(crate) struct Typeset<B> {
    inner: B,
    regular: FontRef<'static>,
    bold: FontRef<'static>,
    /// Text is drawn by `inner` (only measured here).
    measure_only: bool,
}

impl<B> Typeset<B> {
    /// `inner` with text in `regular` and `bold`.
    pub fn new(inner: B, (regular, bold): (FontRef<'static>, FontRef<'static>)) -> Self {
        Typeset {
            inner,
            regular,
            bold,
            measure_only: false,
        }
    }

    /// `inner` drawing its own text (SVG `<text>`), measured with `regular`
    /// and `bold` (the layout of titles, ticks and legends).
    #[cfg(target_arch = "wasm32")]
    pub fn measuring(inner: B, faces: (FontRef<'static>, FontRef<'static>)) -> Self {
        Typeset {
            measure_only: true,
            ..Typeset::new(inner, faces)
        }
    }

    fn scaled<S: BackendTextStyle>(&self, style: &S) -> PxScaleFont<&FontRef<'static>> {
        let face = match style.style() {
            FontStyle::Bold => &self.bold,
            _ => &self.regular,
        };
        face.as_scaled(style.size() as f32)
    }
}

/// The glyphs of `text` with their pen positions, and the advance width.
fn layout(f: &PxScaleFont<&FontRef<'static>>, text: &str) -> (Vec<(GlyphId, f32)>, f32) {
    let mut x = 0.0f32;
    let mut prev: Option<GlyphId> = None;
    let mut out = Vec::new();
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            x += f.kern(p, id);
        }
        out.push((id, x));
        x += f.h_advance(id);
        prev = Some(id);
    }
    (out, x)
}

impl<B: DrawingBackend> DrawingBackend for Typeset<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        p: BackendCoord,
        c: BackendColor,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_pixel(p, c)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        a: BackendCoord,
        b: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_rect(a, b, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.fill_polygon(vert, style)
    }

    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        if self.measure_only {
            return self.inner.draw_text(text, style, pos);
        }
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let f = self.scaled(style);
        let (glyphs, width) = layout(&f, text);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0.0,
            HPos::Center => -0.5 * width,
            HPos::Right => -width,
        };
        let base = match style.anchor().v_pos {
            VPos::Top => f.ascent(),
            VPos::Center => 0.5 * (f.ascent() + f.descent()),
            VPos::Bottom => f.descent(),
        };
        let trans = style.transform();
        let mut pixels = Vec::new();
        for (id, x) in glyphs {
            let g = id.with_scale_and_position(f.scale(), point(x + dx, base));
            if let Some(o) = f.outline_glyph(g) {
                let b = o.px_bounds();
                let (bx, by) = (b.min.x as i32, b.min.y as i32);
                o.draw(|gx, gy, c| {
                    if c > 0.0 {
                        pixels.push((bx + gx as i32, by + gy as i32, c));
                    }
                });
            }
        }
        let (w, h) = self.inner.get_size();
        for (x, y, c) in pixels {
            let (x, y) = trans.transform(x, y);
            let (x, y) = (pos.0 + x, pos.1 + y);
            if x >= 0 && y >= 0 && x < w as i32 && y < h as i32 {
                let alpha = color.alpha * f64::from(c.min(1.0));
                self.inner
                    .draw_pixel((x, y), BackendColor { alpha, ..color })?;
            }
        }
        Ok(())
    }

    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> Result<(u32, u32), DrawingErrorKind<B::ErrorType>> {
        let f = self.scaled(style);
        let (_, width) = layout(&f, text);
        Ok((
            width.ceil() as u32,
            (f.ascent() - f.descent()).ceil() as u32,
        ))
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }
}
