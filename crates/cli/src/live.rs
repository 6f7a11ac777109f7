//! `anima run SCENE --live`: the run joined to `anima-view`'s live server. The runtime speaks through
//! [`anima_run::live::LiveLink`] and the server through its bounded channels; this module is the one
//! place that knows both, so neither crate depends on the other.

use std::time::Duration;

use anima_run::live::{Live, LiveCommand, LiveLink, LiveParam};
use anima_run::run::Progress;
use anima_view::live::{Command, CommandReceiver, Frame, FrameSender, Param};

/// The run's end of the viewer's channels.
pub struct ViewLink {
    pub frames: FrameSender,
    pub commands: CommandReceiver,
}

impl LiveLink for ViewLink {
    fn tell(&mut self, json: String) -> bool {
        self.frames.tell(json)
    }

    fn frame(&mut self, index: usize, time_s: f64, positions: Vec<f32>) {
        self.frames.offer(Frame { index, time_s, positions });
    }

    fn command(&mut self, wait: Option<Duration>) -> Option<LiveCommand> {
        let command = match wait {
            Some(w) => self.commands.wait(w),
            None => self.commands.drain().next(),
        }?;
        Some(match command {
            Command::Pause => LiveCommand::Pause,
            Command::Resume => LiveCommand::Resume,
            Command::Step => LiveCommand::Step,
            Command::Set { index, value } => LiveCommand::Set { index, value },
        })
    }
}

/// The parameters as the viewer offers them (same order: a command's index is the run's).
pub fn view_params(params: &[LiveParam]) -> Vec<Param> {
    params.iter().map(|p| Param { name: p.name.clone(), value: p.value, min: p.min, max: p.max }).collect()
}

/// A progress bar that also tells the page how far the run is (at each whole per cent) and its
/// warnings.
pub struct LiveBar<P> {
    pub inner: P,
    pub live: Live,
    total: u64,
    percent: u64,
}

impl<P> LiveBar<P> {
    pub fn new(inner: P, live: Live) -> Self {
        Self { inner, live, total: 1, percent: u64::MAX }
    }
}

impl<P: Progress> Progress for LiveBar<P> {
    fn begin(&mut self, total: u64) {
        self.total = total.max(1);
        self.inner.begin(total);
    }

    fn advance(&mut self, done: u64) {
        self.inner.advance(done);
        let percent = done.min(self.total) * 100 / self.total;
        if percent != self.percent {
            self.percent = percent;
            self.live.link().tell(format!("{{\"progress\":{}}}", percent as f64 / 100.0));
        }
    }

    fn warn(&mut self, message: &str) {
        self.inner.warn(message);
        let note = serde_json::json!({ "warning": message }).to_string();
        self.live.link().tell(note);
    }

    fn end(&mut self) {
        self.inner.end();
    }
}
