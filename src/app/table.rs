//! The per-configuration table: sortable by every column, rows select in 3D.

use crate::analysis::{Analysis, ConfigRow};
use crate::dataset::Split;
use crate::side::ConfigId;
use eframe::egui::{self, Color32, RichText, Sense};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    Id,
    Arm,
    Split,
    WorstPos,
    WorstOri,
    Rigidity,
}

impl Column {
    const ALL: [Column; 6] = [
        Column::Id,
        Column::Arm,
        Column::Split,
        Column::WorstPos,
        Column::WorstOri,
        Column::Rigidity,
    ];

    fn title(self) -> &'static str {
        match self {
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
    fn text(self, row: &ConfigRow) -> String {
        let number = |x: f64, digits: usize| {
            if x.is_finite() {
                format!("{x:.digits$}")
            } else {
                "—".into()
            }
        };
        match self {
            Column::Id => row.id.clone(),
            Column::Arm => row.config.side.name().into(),
            Column::Split => row.split.name().into(),
            Column::WorstPos => number(row.worst_pos_mm, 3),
            Column::WorstOri => number(row.worst_ori_rad, 5),
            Column::Rigidity => number(row.rigidity_mm, 3),
        }
    }

    fn width(self) -> f32 {
        match self {
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

fn compare(a: &ConfigRow, b: &ConfigRow, column: Column) -> std::cmp::Ordering {
    match column {
        Column::Id => a.id.cmp(&b.id),
        Column::Arm => a.config.side.name().cmp(b.config.side.name()),
        Column::Split => (a.split == Split::Ver).cmp(&(b.split == Split::Ver)),
        Column::WorstPos => a.worst_pos_mm.total_cmp(&b.worst_pos_mm),
        Column::WorstOri => a.worst_ori_rad.total_cmp(&b.worst_ori_rad),
        Column::Rigidity => a.rigidity_mm.total_cmp(&b.rigidity_mm),
    }
}

/// Row order for the current sort.
pub fn sorted_rows(analysis: &Analysis, state: TableState) -> Vec<usize> {
    let mut order: Vec<usize> = (0..analysis.configs.len()).collect();
    order.sort_by(|&i, &j| {
        let o = compare(&analysis.configs[i], &analysis.configs[j], state.column)
            .then_with(|| analysis.configs[i].id.cmp(&analysis.configs[j].id));
        if state.descending { o.reverse() } else { o }
    });
    order
}

/// The configuration with the largest worst |Δd|.
pub fn worst(analysis: &Analysis) -> Option<ConfigId> {
    analysis
        .configs
        .iter()
        .filter(|r| r.worst_pos_mm.is_finite())
        .max_by(|a, b| a.worst_pos_mm.total_cmp(&b.worst_pos_mm))
        .map(|r| r.config)
}

fn cell(ui: &mut egui::Ui, width: f32, text: RichText) {
    ui.add_sized(
        [width, 18.0],
        egui::Label::new(text).truncate().halign(egui::Align::Min),
    );
}

/// Draw the table; returns the configuration whose row was clicked.
pub fn config_table_ui(
    ui: &mut egui::Ui,
    analysis: &Analysis,
    state: &mut TableState,
    selection: Option<ConfigId>,
    scroll_to_selection: bool,
) -> Option<ConfigId> {
    // A narrow panel scrolls the columns sideways (header and rows together).
    egui::ScrollArea::horizontal()
        .id_salt("config table columns")
        .auto_shrink([false, false])
        .show(ui, |ui| {
            table_ui(ui, analysis, state, selection, scroll_to_selection)
        })
        .inner
}

fn table_ui(
    ui: &mut egui::Ui,
    analysis: &Analysis,
    state: &mut TableState,
    selection: Option<ConfigId>,
    scroll_to_selection: bool,
) -> Option<ConfigId> {
    let mut clicked = None;
    // The sort order in words (no arrow glyphs in the default fonts); the sorted title in colour.
    ui.label(
        RichText::new(format!(
            "sorted by {}, {} first — click a title to sort",
            state.column.title(),
            match (state.column, state.descending) {
                (Column::Id | Column::Arm | Column::Split, false) => "a",
                (Column::Id | Column::Arm | Column::Split, true) => "z",
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
                        Column::WorstPos | Column::WorstOri | Column::Rigidity
                    );
                }
            }
        }
    });
    ui.separator();
    let order = sorted_rows(analysis, *state);
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
            let response = ui
                .horizontal(|ui| {
                    ui.set_height(row_height);
                    let strong = |t: String| {
                        let t = RichText::new(t).monospace();
                        if selected { t.color(Color32::WHITE) } else { t }
                    };
                    for column in Column::ALL {
                        cell(ui, column.width(), strong(column.text(row)));
                    }
                })
                .response;
            if selected {
                ui.painter().rect_filled(
                    response.rect,
                    2.0,
                    Color32::from_rgba_unmultiplied(80, 140, 220, 40),
                );
            }
            let r = ui.interact(response.rect, egui::Id::unique(("row", i)), Sense::click());
            if r.clicked() {
                clicked = Some(row.config);
            }
        }
    });
    clicked
}
