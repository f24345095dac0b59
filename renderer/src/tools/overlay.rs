//! The statistics overlay (issue 7 item 7): frame time (rolling median), τ, tiles drawn, late
//! tiles, triangles and pose age, drawn without any font or UI dependency.
//!
//! - Text is rasterised on the CPU with a built-in 5×7 ASCII bitmap font ([`rasterise`], a pure
//!   function) into a small RGBA8 panel on an opaque dark background.
//! - The panel is staged through the frame's staging ring and copied with
//!   `vkCmdCopyBufferToImage` into the top-left corner of the offscreen colour target after the
//!   terrain pass and before the read-back or the blit to the swapchain
//!   (`render::overlay_pass::record_panel_copy`),
//!   so it appears in PNGs and on screen alike and costs one small copy per frame.
//! - A copy cannot blend: the background is opaque (the panel covers ~1–2 % of a frame). The
//!   statistics shown are those of the previous frame of the same channel: the panel is uploaded
//!   with the frame it is drawn on, before that frame's own statistics exist.

use std::collections::VecDeque;

pub use crate::render::overlay_pass::Panel;
use crate::render::stats::FrameStats;

/// Glyph cell: 5 columns × 7 rows.
pub const GLYPH_W: u32 = 5;
pub const GLYPH_H: u32 = 7;
/// Horizontal advance per character and line height, pixels at scale 1.
pub const ADVANCE: u32 = 6;
pub const LINE_HEIGHT: u32 = 9;
/// Margin between the panel edge and the text, pixels at scale 1.
pub const PAD: u32 = 3;
/// Panel colours (sRGB bytes, copied as is into the sRGB target).
pub const BACKGROUND: [u8; 4] = [18, 22, 30, 255];
pub const FOREGROUND: [u8; 4] = [236, 236, 228, 255];
/// Frames in the rolling median of the frame time.
pub const MEDIAN_WINDOW: usize = 60;

/// The classic 5×7 LCD font, printable ASCII 0x20..=0x7E: five column bytes per glyph, bit 0 the
/// top row.
const FONT: [[u8; 5]; 95] = [
    [0x00, 0x00, 0x00, 0x00, 0x00], // ' '
    [0x00, 0x00, 0x5F, 0x00, 0x00], // !
    [0x00, 0x07, 0x00, 0x07, 0x00], // "
    [0x14, 0x7F, 0x14, 0x7F, 0x14], // #
    [0x24, 0x2A, 0x7F, 0x2A, 0x12], // $
    [0x23, 0x13, 0x08, 0x64, 0x62], // %
    [0x36, 0x49, 0x55, 0x22, 0x50], // &
    [0x00, 0x05, 0x03, 0x00, 0x00], // '
    [0x00, 0x1C, 0x22, 0x41, 0x00], // (
    [0x00, 0x41, 0x22, 0x1C, 0x00], // )
    [0x08, 0x2A, 0x1C, 0x2A, 0x08], // *
    [0x08, 0x08, 0x3E, 0x08, 0x08], // +
    [0x00, 0x50, 0x30, 0x00, 0x00], // ,
    [0x08, 0x08, 0x08, 0x08, 0x08], // -
    [0x00, 0x60, 0x60, 0x00, 0x00], // .
    [0x20, 0x10, 0x08, 0x04, 0x02], // /
    [0x3E, 0x51, 0x49, 0x45, 0x3E], // 0
    [0x00, 0x42, 0x7F, 0x40, 0x00], // 1
    [0x42, 0x61, 0x51, 0x49, 0x46], // 2
    [0x21, 0x41, 0x45, 0x4B, 0x31], // 3
    [0x18, 0x14, 0x12, 0x7F, 0x10], // 4
    [0x27, 0x45, 0x45, 0x45, 0x39], // 5
    [0x3C, 0x4A, 0x49, 0x49, 0x30], // 6
    [0x01, 0x71, 0x09, 0x05, 0x03], // 7
    [0x36, 0x49, 0x49, 0x49, 0x36], // 8
    [0x06, 0x49, 0x49, 0x29, 0x1E], // 9
    [0x00, 0x36, 0x36, 0x00, 0x00], // :
    [0x00, 0x56, 0x36, 0x00, 0x00], // ;
    [0x08, 0x14, 0x22, 0x41, 0x00], // <
    [0x14, 0x14, 0x14, 0x14, 0x14], // =
    [0x00, 0x41, 0x22, 0x14, 0x08], // >
    [0x02, 0x01, 0x51, 0x09, 0x06], // ?
    [0x32, 0x49, 0x79, 0x41, 0x3E], // @
    [0x7E, 0x11, 0x11, 0x11, 0x7E], // A
    [0x7F, 0x49, 0x49, 0x49, 0x36], // B
    [0x3E, 0x41, 0x41, 0x41, 0x22], // C
    [0x7F, 0x41, 0x41, 0x22, 0x1C], // D
    [0x7F, 0x49, 0x49, 0x49, 0x41], // E
    [0x7F, 0x09, 0x09, 0x09, 0x01], // F
    [0x3E, 0x41, 0x49, 0x49, 0x7A], // G
    [0x7F, 0x08, 0x08, 0x08, 0x7F], // H
    [0x00, 0x41, 0x7F, 0x41, 0x00], // I
    [0x20, 0x40, 0x41, 0x3F, 0x01], // J
    [0x7F, 0x08, 0x14, 0x22, 0x41], // K
    [0x7F, 0x40, 0x40, 0x40, 0x40], // L
    [0x7F, 0x02, 0x0C, 0x02, 0x7F], // M
    [0x7F, 0x04, 0x08, 0x10, 0x7F], // N
    [0x3E, 0x41, 0x41, 0x41, 0x3E], // O
    [0x7F, 0x09, 0x09, 0x09, 0x06], // P
    [0x3E, 0x41, 0x51, 0x21, 0x5E], // Q
    [0x7F, 0x09, 0x19, 0x29, 0x46], // R
    [0x46, 0x49, 0x49, 0x49, 0x31], // S
    [0x01, 0x01, 0x7F, 0x01, 0x01], // T
    [0x3F, 0x40, 0x40, 0x40, 0x3F], // U
    [0x1F, 0x20, 0x40, 0x20, 0x1F], // V
    [0x3F, 0x40, 0x38, 0x40, 0x3F], // W
    [0x63, 0x14, 0x08, 0x14, 0x63], // X
    [0x07, 0x08, 0x70, 0x08, 0x07], // Y
    [0x61, 0x51, 0x49, 0x45, 0x43], // Z
    [0x00, 0x7F, 0x41, 0x41, 0x00], // [
    [0x02, 0x04, 0x08, 0x10, 0x20], // backslash
    [0x00, 0x41, 0x41, 0x7F, 0x00], // ]
    [0x04, 0x02, 0x01, 0x02, 0x04], // ^
    [0x40, 0x40, 0x40, 0x40, 0x40], // _
    [0x00, 0x01, 0x02, 0x04, 0x00], // `
    [0x20, 0x54, 0x54, 0x54, 0x78], // a
    [0x7F, 0x48, 0x44, 0x44, 0x38], // b
    [0x38, 0x44, 0x44, 0x44, 0x20], // c
    [0x38, 0x44, 0x44, 0x48, 0x7F], // d
    [0x38, 0x54, 0x54, 0x54, 0x18], // e
    [0x08, 0x7E, 0x09, 0x01, 0x02], // f
    [0x08, 0x14, 0x54, 0x54, 0x3C], // g
    [0x7F, 0x08, 0x04, 0x04, 0x78], // h
    [0x00, 0x44, 0x7D, 0x40, 0x00], // i
    [0x20, 0x40, 0x44, 0x3D, 0x00], // j
    [0x7F, 0x10, 0x28, 0x44, 0x00], // k
    [0x00, 0x41, 0x7F, 0x40, 0x00], // l
    [0x7C, 0x04, 0x18, 0x04, 0x78], // m
    [0x7C, 0x08, 0x04, 0x04, 0x78], // n
    [0x38, 0x44, 0x44, 0x44, 0x38], // o
    [0x7C, 0x14, 0x14, 0x14, 0x08], // p
    [0x08, 0x14, 0x14, 0x18, 0x7C], // q
    [0x7C, 0x08, 0x04, 0x04, 0x08], // r
    [0x48, 0x54, 0x54, 0x54, 0x20], // s
    [0x04, 0x3F, 0x44, 0x40, 0x20], // t
    [0x3C, 0x40, 0x40, 0x20, 0x7C], // u
    [0x1C, 0x20, 0x40, 0x20, 0x1C], // v
    [0x3C, 0x40, 0x30, 0x40, 0x3C], // w
    [0x44, 0x28, 0x10, 0x28, 0x44], // x
    [0x0C, 0x50, 0x50, 0x50, 0x3C], // y
    [0x44, 0x64, 0x54, 0x4C, 0x44], // z
    [0x00, 0x08, 0x36, 0x41, 0x00], // {
    [0x00, 0x00, 0x7F, 0x00, 0x00], // |
    [0x00, 0x41, 0x36, 0x08, 0x00], // }
    [0x08, 0x04, 0x08, 0x10, 0x08], // ~
];

/// τ (Greek tau), for the error bound's label.
const TAU: [u8; 5] = [0x04, 0x04, 0x3C, 0x44, 0x04];
/// Drawn for any character the font lacks: an outlined box, so a missing glyph is visible.
pub const UNKNOWN: [u8; 5] = [0x7F, 0x41, 0x41, 0x41, 0x7F];

/// The glyph of `c` (column bytes, bit 0 = top row); [`UNKNOWN`] when the font lacks it.
pub fn glyph(c: char) -> [u8; 5] {
    match c {
        ' '..='~' => FONT[c as usize - 0x20],
        'τ' => TAU,
        // En and em dashes ("no value") look like a hyphen.
        '–' | '—' => FONT['-' as usize - 0x20],
        _ => UNKNOWN,
    }
}

/// The panel size the lines need at integer `scale`: padding, `ADVANCE` per character (the last
/// column's gap dropped), `LINE_HEIGHT` per line (the last line's gap dropped).
pub fn panel_size(lines: &[String], scale: u32) -> (u32, u32) {
    let chars = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
    let n = lines.len() as u32;
    let text_w = (chars * ADVANCE).saturating_sub(ADVANCE - GLYPH_W);
    let text_h = (n * LINE_HEIGHT).saturating_sub(LINE_HEIGHT - GLYPH_H);
    (
        (2 * PAD + text_w) * scale.max(1),
        (2 * PAD + text_h) * scale.max(1),
    )
}

/// Rasterises `lines` into a `width × height` panel: background everywhere, glyph pixels in
/// the foreground colour, each font pixel a `scale × scale` block, text starting at the
/// padding. Anything beyond the panel's edge is clipped (never wrapped).
pub fn rasterise(lines: &[String], width: u32, height: u32, scale: u32) -> Panel {
    let s = scale.max(1);
    let mut rgba = Vec::with_capacity(width as usize * height as usize * 4);
    for _ in 0..width as usize * height as usize {
        rgba.extend_from_slice(&BACKGROUND);
    }
    for (row, line) in lines.iter().enumerate() {
        let y0 = (PAD + row as u32 * LINE_HEIGHT) * s;
        for (col, c) in line.chars().enumerate() {
            let x0 = (PAD + col as u32 * ADVANCE) * s;
            if x0 >= width || y0 >= height {
                continue;
            }
            let g = glyph(c);
            for (gx, bits) in g.iter().enumerate() {
                for gy in 0..GLYPH_H {
                    if bits >> gy & 1 == 0 {
                        continue;
                    }
                    for dy in 0..s {
                        for dx in 0..s {
                            let x = x0 + gx as u32 * s + dx;
                            let y = y0 + gy * s + dy;
                            if x < width && y < height {
                                let o = ((y * width + x) * 4) as usize;
                                rgba[o..o + 4].copy_from_slice(&FOREGROUND);
                            }
                        }
                    }
                }
            }
        }
    }
    Panel {
        width,
        height,
        rgba,
    }
}

/// What the overlay reports about one frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OverlayInfo {
    pub tau_px: f64,
    pub tiles_drawn: u32,
    pub tiles_late: u32,
    pub triangles: u64,
}

impl OverlayInfo {
    pub fn from_stats(s: &FrameStats, tau_px: f64) -> Self {
        Self {
            tau_px,
            tiles_drawn: s.tiles_drawn,
            tiles_late: s.tiles_late,
            triangles: s.triangles,
        }
    }
}

/// The overlay's text: frame time (median over the last frames), τ, tiles and late tiles,
/// triangles, pose age. "–" stands for what is not known yet (before the first frame) or not
/// given (no pose stream).
pub fn overlay_lines(
    frame_ms_median: Option<f64>,
    info: Option<&OverlayInfo>,
    pose_age_ms: Option<f64>,
) -> Vec<String> {
    let dash = || "–".to_string();
    let tri = |n: u64| {
        if n >= 1_000_000 {
            format!("{:.2}M", n as f64 / 1e6)
        } else if n >= 10_000 {
            format!("{:.1}k", n as f64 / 1e3)
        } else {
            n.to_string()
        }
    };
    vec![
        format!(
            "frame {} ms",
            frame_ms_median.map_or_else(dash, |m| format!("{m:.1}"))
        ),
        format!(
            "τ {} px",
            info.map_or_else(dash, |i| format!("{:.2}", i.tau_px))
        ),
        match info {
            Some(i) => format!("tiles {} late {}", i.tiles_drawn, i.tiles_late),
            None => "tiles – late –".to_string(),
        },
        format!("tris {}", info.map_or_else(dash, |i| tri(i.triangles))),
        format!(
            "pose age {}",
            pose_age_ms.map_or_else(dash, |a| format!("{a:.0} ms"))
        ),
    ]
}

/// The median of `v` (0 values: `None`).
pub fn median(v: impl IntoIterator<Item = f64>) -> Option<f64> {
    let mut s: Vec<f64> = v.into_iter().collect();
    if s.is_empty() {
        return None;
    }
    s.sort_by(f64::total_cmp);
    let n = s.len();
    Some(if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    })
}

/// Integer scale of the font for a target: 1 below 1280 pixels wide, 2 up to 2559, then 3.
pub fn scale_for(target_width: u32) -> u32 {
    (target_width / 1280 + 1).min(3)
}

/// The overlay of one channel: on/off, the recent frame times and the last frame's numbers.
#[derive(Debug, Clone)]
pub struct OverlayState {
    on: bool,
    frame_ms: VecDeque<f64>,
    last: Option<OverlayInfo>,
}

impl OverlayState {
    pub fn new(on: bool) -> Self {
        Self {
            on,
            frame_ms: VecDeque::with_capacity(MEDIAN_WINDOW),
            last: None,
        }
    }

    pub fn is_on(&self) -> bool {
        self.on
    }

    pub fn set(&mut self, on: bool) {
        self.on = on;
    }

    pub fn toggle(&mut self) {
        self.on = !self.on;
    }

    /// Records a finished frame: its time (ms) and its numbers. Kept while off too, so the
    /// panel is right from the first frame it is shown.
    pub fn record(&mut self, frame_ms: f64, info: OverlayInfo) {
        if self.frame_ms.len() == MEDIAN_WINDOW {
            self.frame_ms.pop_front();
        }
        self.frame_ms.push_back(frame_ms);
        self.last = Some(info);
    }

    /// Records a frame's numbers without a frame time (the first frame of a session).
    pub fn record_info(&mut self, info: OverlayInfo) {
        self.last = Some(info);
    }

    pub fn lines(&self, pose_age_ms: Option<f64>) -> Vec<String> {
        overlay_lines(
            median(self.frame_ms.iter().copied()),
            self.last.as_ref(),
            pose_age_ms,
        )
    }

    /// The panel for a target of `target` pixels, clipped to it; `None` when off.
    pub fn panel(&self, target: (u32, u32), pose_age_ms: Option<f64>) -> Option<Panel> {
        if !self.on {
            return None;
        }
        let lines = self.lines(pose_age_ms);
        let s = scale_for(target.0);
        let (w, h) = panel_size(&lines, s);
        Some(rasterise(&lines, w.min(target.0), h.min(target.1), s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lit(p: &Panel) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        for y in 0..p.height {
            for x in 0..p.width {
                let px = p.pixel(x, y);
                if px == FOREGROUND {
                    v.push((x, y));
                } else {
                    assert_eq!(px, BACKGROUND, "({x}, {y})");
                }
            }
        }
        v
    }

    #[test]
    fn glyph_bits_match_the_font() {
        // '1': a vertical bar in column 2, a serif at (1, 1) and a foot along row 6.
        let one = glyph('1');
        assert_eq!(one, [0x00, 0x42, 0x7F, 0x40, 0x00]);
        let p = rasterise(&["1".to_string()], PAD + 5, PAD + 7, 1);
        let px: Vec<(u32, u32)> = lit(&p)
            .into_iter()
            .map(|(x, y)| (x - PAD, y - PAD))
            .collect();
        let mut expect = vec![(1, 1), (1, 6), (3, 6)];
        expect.extend((0..7).map(|y| (2, y)));
        expect.sort_by_key(|&(x, y)| (y, x));
        assert_eq!(px, expect);
        // Every printable ASCII character has a glyph (space is empty, all others light
        // something) within the 7 rows.
        assert_eq!(glyph(' '), [0; 5]);
        for c in '!'..='~' {
            assert!(glyph(c).iter().any(|&b| b != 0), "{c:?} is blank");
            assert!(glyph(c).iter().all(|&b| b < 0x80), "{c:?} uses an 8th row");
            assert_ne!(glyph(c), UNKNOWN, "{c:?}");
        }
        // Row 0 of 'T' is the bar: columns 0..5 all lit.
        assert!(glyph('T').iter().all(|&b| b & 1 == 1));
    }

    #[test]
    fn unknown_characters_draw_a_box_and_dashes_a_hyphen() {
        assert_eq!(glyph('é'), UNKNOWN);
        assert_eq!(glyph('\u{1F600}'), UNKNOWN);
        assert_eq!(glyph('\t'), UNKNOWN);
        assert_eq!(glyph('–'), glyph('-'));
        assert_ne!(glyph('τ'), UNKNOWN);
        let p = rasterise(&["é".to_string()], 11, 13, 1);
        // The box outline: two full columns of 7 and three columns of top and bottom pixels.
        assert_eq!(lit(&p).len(), 7 + 7 + 3 * 2);
    }

    #[test]
    fn text_is_clipped_at_the_panel_edge() {
        let line = "8888888888".to_string();
        let (w, h) = panel_size(std::slice::from_ref(&line), 1);
        assert_eq!((w, h), (2 * PAD + 10 * ADVANCE - 1, 2 * PAD + GLYPH_H));
        let full = rasterise(std::slice::from_ref(&line), w, h, 1);
        // Narrower panel: the same pixels where both exist, nothing outside, no wrap.
        let narrow = rasterise(std::slice::from_ref(&line), 20, h - 2, 1);
        assert_eq!(narrow.rgba.len(), 20 * (h - 2) as usize * 4);
        for y in 0..h - 2 {
            for x in 0..20 {
                assert_eq!(narrow.pixel(x, y), full.pixel(x, y), "({x}, {y})");
            }
        }
        // The third '8' starts at x = 15 and is cut after 5 columns, its bottom row cut off.
        assert!(lit(&narrow).iter().any(|&(x, _)| x == 19));
        // A second line starting in the bottom padding shows only its top row: clipped, not
        // wrapped or moved ('8' lights columns 1..=3 of its top row).
        let two = rasterise(&[line.clone(), line.clone()], w, h, 1);
        assert_eq!(
            two.rgba[..((h - 1) * w * 4) as usize],
            full.rgba[..((h - 1) * w * 4) as usize]
        );
        let bottom: Vec<u32> = lit(&two)
            .into_iter()
            .filter(|&(_, y)| y == h - 1)
            .map(|(x, _)| x)
            .collect();
        let expect: Vec<u32> = (0..10)
            .flat_map(|c| (1..=3).map(move |k| PAD + c * ADVANCE + k))
            .collect();
        assert_eq!(bottom, expect);
        // Scale 2: every font pixel becomes a 2×2 block.
        let big = rasterise(std::slice::from_ref(&line), 2 * w, 2 * h, 2);
        for y in 0..h {
            for x in 0..w {
                let p = full.pixel(x, y);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    assert_eq!(big.pixel(2 * x + dx, 2 * y + dy), p);
                }
            }
        }
        // Zero-sized panels are empty, not a panic.
        assert!(rasterise(&[line], 0, 0, 1).rgba.is_empty());
    }

    #[test]
    fn overlay_text_and_rolling_median() {
        let info = OverlayInfo {
            tau_px: 1.0,
            tiles_drawn: 523,
            tiles_late: 2,
            triangles: 1_234_567,
        };
        let l = overlay_lines(Some(12.34), Some(&info), None);
        assert_eq!(
            l,
            [
                "frame 12.3 ms",
                "τ 1.00 px",
                "tiles 523 late 2",
                "tris 1.23M",
                "pose age –"
            ]
        );
        assert_eq!(
            overlay_lines(None, Some(&info), Some(17.4))[4],
            "pose age 17 ms"
        );
        assert_eq!(overlay_lines(None, Some(&info), None)[0], "frame – ms");
        // Before the first frame nothing is known: dashes, not zeros.
        let mut s = OverlayState::new(false);
        assert_eq!(
            s.lines(None),
            [
                "frame – ms",
                "τ – px",
                "tiles – late –",
                "tris –",
                "pose age –"
            ]
        );
        assert!(s.panel((320, 180), None).is_none());
        for k in 0..100 {
            // One slow frame among fast ones does not move the median.
            s.record(
                if k == 99 {
                    500.0
                } else {
                    10.0 + (k % 3) as f64
                },
                info,
            );
        }
        assert_eq!(median(s.frame_ms.iter().copied()), Some(11.0));
        assert_eq!(s.frame_ms.len(), MEDIAN_WINDOW);
        s.toggle();
        let p = s.panel((320, 180), None).unwrap();
        let lines = s.lines(None);
        assert_eq!((p.width, p.height), panel_size(&lines, 1));
        assert_eq!(p, rasterise(&lines, p.width, p.height, 1));
        // Clipped to a tiny target.
        let p = s.panel((40, 20), None).unwrap();
        assert_eq!((p.width, p.height), (40, 20));
        assert_eq!(scale_for(1920), 2);
        assert_eq!(median([3.0, 1.0]), Some(2.0));
    }
}
