//! The per-configuration table: sortable by every column, rows select in 3D, a check box (or the X
//! key on the selection) leaves a configuration out of the calibration, the quality flag of each
//! configuration (reason and size, coloured by severity) in its own column.

use crate::analysis::{Analysis, ConfigRow};
use crate::app::colormap;
use crate::dataset::Split;
use crate::quality::Flag;
use crate::side::ConfigId;
use eframe::egui::{self, Color32, RichText, Sense};
use std::collections::BTreeMap;

/// Each suspect configuration's flags, most severe first ([`crate::quality::Screening::by_config`]).
pub type Flags<'a> = BTreeMap<ConfigId, Vec<&'a Flag>>;

/// What a click in the table asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableAction {
    Select(ConfigId),
    /// The row's "use" box: leave the configuration out, or take it back in.
    ToggleExclude(ConfigId),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// Used for the calibration (not excluded).
    Use,
    Id,
    Arm,
    Split,
    WorstPos,
    WorstOri,
    Rigidity,
    /// The most severe quality flag.
    Flag,
}

impl Column {
    const ALL: [Column; 8] = [
        Column::Use,
        Column::Id,
        Column::Arm,
        Column::Split,
        Column::Flag,
        Column::WorstPos,
        Column::WorstOri,
        Column::Rigidity,
    ];

    fn title(self) -> &'static str {
        match self {
            Column::Use => "use",
            Column::Flag => "flag (mm)",
            Column::Id => "id",
            Column::Arm => "arm",
            Column::Split => "split",
            Column::WorstPos => "|Δd| max (mm)",
            Column::WorstOri => "Δo max (rad)",
            Column::Rigidity => "rigidity (mm)",
        }
    }

    fn tooltip(self) -> &'static str {
        match self {
            Column::Use => {
                "Used for the calibration and the figures; untick (or select and press X) to leave the configuration out and calibrate again at once"
            }
            Column::Flag => {
                "Why the screening finds the configuration suspect and how large the problem is, mm (dualcal calibrate's flags; hover a flag for the whole reason). Magenta just past the threshold, red at 8× it."
            }
            Column::Id => "Configuration id from the dataset",
            Column::Arm => "Which arm was measured",
            Column::Split => "cal: used for identification; ver: verification only",
            Column::WorstPos => {
                "Largest |Δd| (measured minus model distance) over every relative and collaborative pair involving this configuration, mm"
            }
            Column::WorstOri => {
                "Largest Δo over every relative and collaborative pair involving this configuration, rad"
            }
            Column::Rigidity => {
                "Largest deviation of the measured reflector triangle's sides from the model's, mm (a bad reflector reading shows here)"
            }
        }
    }

    /// What the column shows for `row`.
    fn text(self, row: &ConfigRow, flags: &Flags) -> String {
        let number = |x: f64, digits: usize| {
            if x.is_finite() {
                format!("{x:.digits$}")
            } else {
                "—".into()
            }
        };
        match self {
            Column::Use => String::new(),
            Column::Flag => flags.get(&row.config).map_or_else(String::new, |f| {
                format!("{} {}", f[0].kind.label(), number(f[0].size_mm, 2))
            }),
            Column::Id => row.id.clone(),
            Column::Arm => row.config.side.name().into(),
            Column::Split => row.split.name().into(),
            Column::WorstPos => number(row.worst_pos_mm, 3),
            Column::WorstOri => row
                .worst_ori_rad
                .map_or_else(|| "–".to_string(), |v| number(v, 5)),
            Column::Rigidity => number(row.rigidity_mm, 3),
        }
    }

    fn width(self) -> f32 {
        match self {
            Column::Use => 28.0,
            Column::Flag => 120.0,
            Column::Id => 64.0,
            Column::Arm => 40.0,
            Column::Split => 36.0,
            _ => 88.0,
        }
    }
}

/// Sort state of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableState {
    pub column: Column,
    pub descending: bool,
}

impl Default for TableState {
    fn default() -> Self {
        Self {
            column: Column::WorstPos,
            descending: true,
        }
    }
}

fn compare(a: &ConfigRow, b: &ConfigRow, column: Column, flags: &Flags) -> std::cmp::Ordering {
    let severity = |r: &ConfigRow| flags.get(&r.config).map_or(0.0, |f| f[0].severity());
    match column {
        Column::Use => a.excluded.cmp(&b.excluded),
        Column::Flag => severity(a).total_cmp(&severity(b)),
        Column::Id => a.id.cmp(&b.id),
        Column::Arm => a.config.side.name().cmp(b.config.side.name()),
        Column::Split => (a.split == Split::Ver).cmp(&(b.split == Split::Ver)),
        Column::WorstPos => a.worst_pos_mm.total_cmp(&b.worst_pos_mm),
        Column::WorstOri => a
            .worst_ori_rad
            .unwrap_or(-1.0)
            .total_cmp(&b.worst_ori_rad.unwrap_or(-1.0)),
        Column::Rigidity => a.rigidity_mm.total_cmp(&b.rigidity_mm),
    }
}

/// Row order for the current sort.
pub fn sorted_rows(analysis: &Analysis, flags: &Flags, state: TableState) -> Vec<usize> {
    let mut order: Vec<usize> = (0..analysis.configs.len()).collect();
    crate::sort::sort_by(&mut order, |&i, &j| {
        let o = compare(
            &analysis.configs[i],
            &analysis.configs[j],
            state.column,
            flags,
        )
        .then_with(|| analysis.configs[i].id.cmp(&analysis.configs[j].id));
        if state.descending { o.reverse() } else { o }
    });
    order
}

/// The configuration with the largest worst |Δd| (of those used).
pub fn worst(analysis: &Analysis) -> Option<ConfigId> {
    analysis
        .configs
        .iter()
        .filter(|r| r.worst_pos_mm.is_finite() && !r.excluded)
        .max_by(|a, b| a.worst_pos_mm.total_cmp(&b.worst_pos_mm))
        .map(|r| r.config)
}

fn cell(ui: &mut egui::Ui, width: f32, text: RichText) {
    ui.add_sized(
        [width, 18.0],
        egui::Label::new(text).truncate().halign(egui::Align::Min),
    );
}

/// Draw the table; returns what a click asked for.
pub fn config_table_ui(
    ui: &mut egui::Ui,
    analysis: &Analysis,
    flags: &Flags,
    state: &mut TableState,
    selection: Option<ConfigId>,
    scroll_to_selection: bool,
) -> Option<TableAction> {
    // A narrow panel scrolls the columns sideways (header and rows together).
    egui::ScrollArea::horizontal()
        .id_salt("config table columns")
        .auto_shrink([false, false])
        .show(ui, |ui| {
            table_ui(ui, analysis, flags, state, selection, scroll_to_selection)
        })
        .inner
}

/// The sort order in words and the column titles, which sort when clicked.
fn header_ui(ui: &mut egui::Ui, state: &mut TableState) {
    // No arrow glyphs in the default fonts; the sorted title in colour.
    ui.label(
        RichText::new(format!(
            "sorted by {}, {} first — click a title to sort",
            state.column.title(),
            match (state.column, state.descending) {
                (Column::Id | Column::Arm | Column::Split, false) => "a",
                (Column::Id | Column::Arm | Column::Split, true) => "z",
                (Column::Use, false) => "used",
                (Column::Use, true) => "excluded",
                (Column::Flag, true) => "most severe",
                (Column::Flag, false) => "unflagged",
                (_, true) => "largest",
                (_, false) => "smallest",
            }
        ))
        .small()
        .color(Color32::GRAY),
    );
    ui.horizontal(|ui| {
        for column in Column::ALL {
            let mut title = RichText::new(column.title()).strong();
            if state.column == column {
                title = title.color(Color32::from_rgb(120, 180, 240));
            }
            let r = ui
                .add_sized(
                    [column.width(), 20.0],
                    egui::Button::new(title).frame(false),
                )
                .on_hover_text(column.tooltip());
            if r.clicked() {
                if state.column == column {
                    state.descending = !state.descending;
                } else {
                    state.column = column;
                    state.descending = matches!(
                        column,
                        Column::WorstPos
                            | Column::WorstOri
                            | Column::Rigidity
                            | Column::Flag
                            | Column::Use
                    );
                }
            }
        }
    });
}

/// One row's cells; whether its "use" box was clicked.
fn row_cells(
    ui: &mut egui::Ui,
    row: &ConfigRow,
    flags: &Flags,
    style: &dyn Fn(String) -> RichText,
    row_height: f32,
) -> bool {
    let flag = flags.get(&row.config).map(|f| f[0]);
    let mut toggled = false;
    for column in Column::ALL {
        match column {
            Column::Use => {
                let mut used = !row.excluded;
                let r = ui
                    .add_sized(
                        [column.width(), row_height],
                        egui::Checkbox::without_text(&mut used),
                    )
                    .on_hover_text(if row.excluded {
                        "Excluded: tick to use it again (and calibrate again)"
                    } else {
                        "Untick to leave it out and calibrate again (or press X)"
                    });
                let label = format!("use {}", row.id);
                r.widget_info(|| {
                    egui::WidgetInfo::selected(egui::Role::CheckBox, true, !row.excluded, &label)
                });
                toggled |= r.clicked();
            }
            Column::Flag => {
                let mut text = style(column.text(row, flags));
                if let Some(f) = flag
                    && !row.excluded
                {
                    text = text.color(colormap::flag_color32(f.severity()));
                }
                let r = ui.add_sized(
                    [column.width(), 18.0],
                    egui::Label::new(text).truncate().halign(egui::Align::Min),
                );
                if let Some(f) = flag {
                    r.on_hover_text(format!(
                        "{} (line {}): {}\nsize {:.3} mm, threshold {:.3} mm",
                        f.id, f.line, f.reason, f.size_mm, f.threshold_mm
                    ));
                }
            }
            _ => cell(ui, column.width(), style(column.text(row, flags))),
        }
    }
    toggled
}

fn table_ui(
    ui: &mut egui::Ui,
    analysis: &Analysis,
    flags: &Flags,
    state: &mut TableState,
    selection: Option<ConfigId>,
    scroll_to_selection: bool,
) -> Option<TableAction> {
    let mut clicked = None;
    header_ui(ui, state);
    ui.separator();
    let order = sorted_rows(analysis, flags, *state);
    let row_height = 20.0;
    let mut scroll = egui::ScrollArea::vertical()
        .auto_shrink([false, false])
        .id_salt("config table");
    if scroll_to_selection
        && let Some(pos) = order
            .iter()
            .position(|&i| selection == Some(analysis.configs[i].config))
    {
        let spacing = ui.spacing().item_spacing.y;
        scroll =
            scroll.vertical_scroll_offset((pos as f32 * (row_height + spacing) - 60.0).max(0.0));
    }
    scroll.show_rows(ui, row_height, order.len(), |ui, range| {
        for &i in &order[range] {
            let row = &analysis.configs[i];
            let selected = selection == Some(row.config);
            let mut toggled = false;
            let response = ui
                .horizontal(|ui| {
                    ui.set_height(row_height);
                    let style = |t: String| {
                        let mut t = RichText::new(t).monospace();
                        if row.excluded {
                            t = t.strikethrough().color(Color32::GRAY);
                        } else if selected {
                            t = t.color(Color32::WHITE);
                        }
                        t
                    };
                    toggled = row_cells(ui, row, flags, &style, row_height);
                })
                .response;
            if selected {
                ui.painter().rect_filled(
                    response.rect,
                    2.0,
                    Color32::from_rgba_unmultiplied(80, 140, 220, 40),
                );
            }
            if toggled {
                clicked = Some(TableAction::ToggleExclude(row.config));
                continue;
            }
            // The rest of the row selects (not the "use" box, which must keep its own clicks).
            let mut rest = response.rect;
            rest.min.x += Column::Use.width() + ui.spacing().item_spacing.x;
            let r = ui.interact(rest, egui::Id::unique(("row", i)), Sense::click());
            if r.clicked() {
                clicked = Some(TableAction::Select(row.config));
            }
        }
    });
    clicked
}
