//! The app's one event channel: background tasks, file dialogs and screenshots report here, and the
//! app drains it once per frame ([`EventChannel::drain`]).
//!
//! Sending never blocks (a task stepped from the frame loop sends from the UI thread itself) and wakes
//! the UI. A calibration reports every outer iteration; those events are sent with
//! [`EventSender::send_droppable`] and dropped while [`MAX_QUEUED_DROPPABLE`] of them are waiting, so a
//! UI that falls behind only loses points of its curves (the final result carries the whole history).

pub use super::command::FileReply;
use eframe::egui;
use std::any::Any;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

/// How many droppable events may wait before more are dropped.
pub const MAX_QUEUED_DROPPABLE: usize = 512;

/// Tells one task's events from another's (a replaced task may still report).
pub type TaskId = u64;

/// What a task sends on the app's channel: one of its own events (of its `Work::Event` type, which
/// the job that started it reads back: `super::job`), or that it stopped without reporting its end.
pub enum TaskReport {
    Event(Box<dyn Any + Send>),
    /// The work panicked (always the task's last report).
    Failed(String),
}

/// Something that happened off the frame.
pub enum AppEvent {
    /// A background task reported.
    Task(TaskId, TaskReport),
    /// A file dialog answered.
    File(FileReply),
    /// The window's picture, as requested for "Export plots as PNG".
    Screenshot(Arc<egui::ColorImage>),
}

struct Queued {
    event: AppEvent,
    droppable: bool,
}

/// The sending end, cloned into every task, dialog and callback.
#[derive(Clone)]
pub struct EventSender {
    sender: Sender<Queued>,
    /// Droppable events sent and not yet drained.
    queued_droppable: Arc<AtomicUsize>,
    repaint: Option<egui::Context>,
}

impl EventSender {
    /// Send an event that must arrive.
    pub fn send(&self, event: AppEvent) {
        self.enqueue(event, false);
    }

    /// Send an event that may be dropped while the UI is behind.
    pub fn send_droppable(&self, event: AppEvent) {
        if self.queued_droppable.load(Ordering::Relaxed) < MAX_QUEUED_DROPPABLE {
            self.queued_droppable.fetch_add(1, Ordering::Relaxed);
            self.enqueue(event, true);
        }
    }

    fn enqueue(&self, event: AppEvent, droppable: bool) {
        // A closed channel means the app is gone: nobody is left to tell.
        if self.sender.send(Queued { event, droppable }).is_ok()
            && let Some(ctx) = &self.repaint
        {
            ctx.request_repaint();
        }
    }
}

/// The channel the app owns.
pub struct EventChannel {
    sender: EventSender,
    receiver: Receiver<Queued>,
}

impl EventChannel {
    /// A channel whose senders wake `repaint` (none in unit tests).
    pub fn new(repaint: Option<egui::Context>) -> Self {
        let (sender, receiver) = channel();
        Self {
            sender: EventSender {
                sender,
                queued_droppable: Arc::new(AtomicUsize::new(0)),
                repaint,
            },
            receiver,
        }
    }

    pub fn sender(&self) -> &EventSender {
        &self.sender
    }

    /// Every event that has arrived, in order, without waiting.
    pub fn drain(&self) -> Vec<AppEvent> {
        let mut events = Vec::new();
        while let Ok(Queued { event, droppable }) = self.receiver.try_recv() {
            if droppable {
                self.sender.queued_droppable.fetch_sub(1, Ordering::Relaxed);
            }
            events.push(event);
        }
        events
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn droppable_events_are_dropped_only_while_too_many_wait() {
        let channel = EventChannel::new(None);
        let sender = channel.sender().clone();
        for _ in 0..MAX_QUEUED_DROPPABLE + 10 {
            sender.send_droppable(AppEvent::File(FileReply::Cancelled));
        }
        sender.send(AppEvent::File(FileReply::Cancelled));
        assert_eq!(channel.drain().len(), MAX_QUEUED_DROPPABLE + 1);
        // Drained, there is room again.
        sender.send_droppable(AppEvent::File(FileReply::Cancelled));
        assert_eq!(channel.drain().len(), 1);
    }
}
