//! The two channels between a running simulation and the page of `anima run SCENE --live`, and the
//! page's command language. This module knows nothing of sockets: the server (`--live`'s WebSocket)
//! feeds it the page's text messages and the run's frames, the CLI wires it to the run. Keeping it
//! apart keeps every check of what a page may ask for in one place, testable without a browser.
//!
//! - **Frames, run → page**: a bounded channel ([`FRAME_QUEUE`] frames). The run offers each frame
//!   with [`FrameSender::offer`], which never blocks: when the page reads slower than the run computes,
//!   the frame is dropped and counted ([`FrameSender::dropped`]), so a slow or stalled page never slows
//!   the simulation. The page sees a gap in frame numbers, never a stall.
//! - **Commands, page → run**: [`Command::parse`] turns one text message into a command or an error
//!   message for the page; a command reaches the run through a bounded channel the run drains at its
//!   next control step ([`CommandReceiver::drain`]), so a parameter change applies at the next control
//!   step (Nunes 2006's on-line modification of controller parameters).
//!
//! The language is one line of text, because the page sends a handful of words:
//! `pause`, `resume`, `step` (one frame, then paused), and `set NAME VALUE` for a controller
//! parameter the controller file names. Anything else, a name the table lacks, a value that is not a
//! finite number or lies outside the parameter's range, or a message over [`MAX_COMMAND_BYTES`], is an
//! error message back to the page, never a panic, and the run does not see it.

use std::sync::mpsc;

/// Frames that may wait for the page; the run drops a frame rather than wait when they are all taken.
pub const FRAME_QUEUE: usize = 8;

/// Commands that may wait for the run's next control step; more are refused with an error message.
pub const COMMAND_QUEUE: usize = 64;

/// The longest command the page may send; a longer message is refused unread.
pub const MAX_COMMAND_BYTES: usize = 256;

/// One controller parameter the page may set, as the controller file names it, with the range a
/// slider covers. The range comes from the run (the controller's own bounds); a value outside it is
/// refused, not clamped, so the page learns that it asked for something the controller does not take.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub name: String,
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

/// What the page may ask of a running simulation.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    Pause,
    Resume,
    /// Compute one frame, then stay paused.
    Step,
    /// Set controller parameter `params[index]` to `value` at the next control step.
    Set {
        index: usize,
        value: f64,
    },
}

impl Command {
    /// The command in `text`, checked against the parameters the run offers; an `Err` is the message
    /// to send back to the page.
    pub fn parse(text: &str, params: &[Param]) -> Result<Command, String> {
        if text.len() > MAX_COMMAND_BYTES {
            return Err(format!("command refused: longer than {MAX_COMMAND_BYTES} bytes"));
        }
        let mut words = text.split_ascii_whitespace();
        let command = match (words.next(), words.next(), words.next()) {
            (Some("pause"), None, None) => Command::Pause,
            (Some("resume"), None, None) => Command::Resume,
            (Some("step"), None, None) => Command::Step,
            (Some("set"), Some(name), Some(value)) => {
                let Some(index) = params.iter().position(|p| p.name == name) else {
                    return Err(format!("unknown parameter {}", shown(name)));
                };
                let p = &params[index];
                let value: f64 =
                    value.parse().map_err(|_| format!("{}: {} is not a number", p.name, shown(value)))?;
                if !value.is_finite() {
                    return Err(format!("{}: {value} is not a finite number", p.name));
                }
                if !(p.min..=p.max).contains(&value) {
                    return Err(format!("{}: {value} is outside [{}, {}]", p.name, p.min, p.max));
                }
                Command::Set { index, value }
            }
            _ => {
                return Err(format!(
                    "unknown command {}: say pause, resume, step or set NAME VALUE",
                    shown(text)
                ));
            }
        };
        if words.next().is_some() {
            return Err(format!("unknown command {}: too many words", shown(text)));
        }
        Ok(command)
    }
}

/// `text` quoted for an error message, cut to a readable length (the page may send anything).
fn shown(text: &str) -> String {
    const MAX: usize = 40;
    let cut: String = text.chars().take(MAX).collect();
    if cut.len() < text.len() { format!("{cut:?}…") } else { format!("{cut:?}") }
}

/// One frame for the page: its number, time and the positions of what moves (x, y, z per point, in
/// metres, in the order the viewer's glTF lists them). `f32`, as the glTF and three.js hold them.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub index: usize,
    pub time_s: f64,
    pub positions: Vec<f32>,
}

/// The run's end of the frame channel. See the module docs for why it drops rather than waits.
/// (tokio's channel: the run offers from its own thread without a runtime, the server awaits.)
/// Beside the frames it carries the run's notes (text for the page: what to draw, progress,
/// warnings, a parameter change taken), bounded to [`COMMAND_QUEUE`] and dropped likewise.
#[derive(Debug)]
pub struct FrameSender {
    tx: tokio::sync::mpsc::Sender<Frame>,
    notes: tokio::sync::mpsc::Sender<String>,
    dropped: usize,
}

/// The server's end of the frame channel: the frames, and the run's notes.
#[derive(Debug)]
pub struct FrameReceiver(pub tokio::sync::mpsc::Receiver<Frame>, pub tokio::sync::mpsc::Receiver<String>);

/// A bounded frame channel of [`FRAME_QUEUE`] frames (and [`COMMAND_QUEUE`] notes).
pub fn frame_channel() -> (FrameSender, FrameReceiver) {
    let (tx, rx) = tokio::sync::mpsc::channel(FRAME_QUEUE);
    let (notes, notes_rx) = tokio::sync::mpsc::channel(COMMAND_QUEUE);
    (FrameSender { tx, notes, dropped: 0 }, FrameReceiver(rx, notes_rx))
}

impl Frame {
    /// The frame as the page reads it from a binary WebSocket message: the index as a little-endian
    /// u32, the time as a little-endian f64, then the positions as little-endian f32s.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(12 + 4 * self.positions.len());
        bytes.extend_from_slice(&u32::try_from(self.index).unwrap_or(u32::MAX).to_le_bytes());
        bytes.extend_from_slice(&self.time_s.to_le_bytes());
        for x in &self.positions {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
        bytes
    }
}

/// The parameters as the page's first message: `{"params":[{"name":…,"value":…,"min":…,"max":…},…]}`.
pub fn params_json(params: &[Param]) -> String {
    let items: Vec<String> = params
        .iter()
        .map(|p| {
            let name: String =
                p.name.chars().filter(|c| c.is_ascii_alphanumeric() || "_-.".contains(*c)).collect();
            format!("{{\"name\":\"{name}\",\"value\":{},\"min\":{},\"max\":{}}}", p.value, p.min, p.max)
        })
        .collect();
    format!("{{\"params\":[{}]}}", items.join(","))
}

impl FrameSender {
    /// Hands `frame` to the page if there is room, else drops it; never blocks. Returns whether it was
    /// queued. A page that has gone away is not an error for the run: the frame is dropped.
    pub fn offer(&mut self, frame: Frame) -> bool {
        let queued = self.tx.try_send(frame).is_ok();
        self.dropped += usize::from(!queued);
        queued
    }

    /// Hands a note (one text message) to the page if there is room, else drops it; never blocks.
    pub fn tell(&mut self, text: String) -> bool {
        self.notes.try_send(text).is_ok()
    }

    /// Frames dropped so far because the page was slow or gone.
    pub fn dropped(&self) -> usize {
        self.dropped
    }
}

/// The server's end of the command channel.
#[derive(Debug, Clone)]
pub struct CommandSender(mpsc::SyncSender<Command>);

/// The run's end of the command channel.
#[derive(Debug)]
pub struct CommandReceiver(mpsc::Receiver<Command>);

/// A bounded command channel of [`COMMAND_QUEUE`] commands.
pub fn command_channel() -> (CommandSender, CommandReceiver) {
    let (tx, rx) = mpsc::sync_channel(COMMAND_QUEUE);
    (CommandSender(tx), CommandReceiver(rx))
}

impl CommandSender {
    /// Passes a checked command to the run; an `Err` is the message for the page (the run is busy or
    /// has ended). Never blocks the server.
    pub fn send(&self, command: Command) -> Result<(), String> {
        self.0.try_send(command).map_err(|e| match e {
            mpsc::TrySendError::Full(_) => {
                "the run has not yet taken the earlier commands; try again".to_owned()
            }
            mpsc::TrySendError::Disconnected(_) => "the run has ended".to_owned(),
        })
    }
}

impl CommandReceiver {
    /// The commands that arrived since the last call, oldest first; never blocks the run.
    pub fn drain(&self) -> impl Iterator<Item = Command> + '_ {
        self.0.try_iter()
    }

    /// The next command, waiting up to `wait` for one (a paused run waits; `None` when none came or
    /// the server has gone).
    pub fn wait(&self, wait: std::time::Duration) -> Option<Command> {
        self.0.recv_timeout(wait).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Vec<Param> {
        vec![Param { name: "swing_hip".into(), value: 0.5, min: -1.0, max: 1.0 }]
    }

    #[test]
    fn the_page_s_words_parse() {
        let p = params();
        assert_eq!(Command::parse("pause", &p), Ok(Command::Pause));
        assert_eq!(Command::parse(" resume\n", &p), Ok(Command::Resume));
        assert_eq!(Command::parse("step", &p), Ok(Command::Step));
        assert_eq!(Command::parse("set swing_hip -0.25", &p), Ok(Command::Set { index: 0, value: -0.25 }));
        assert_eq!(Command::parse("set swing_hip 1", &p), Ok(Command::Set { index: 0, value: 1.0 }));
    }

    #[test]
    fn hostile_commands_are_errors_not_panics() {
        let p = params();
        for bad in [
            "",
            "PAUSE",
            "pause now",
            "set",
            "set swing_hip",
            "set swing_hip 0.1 0.2",
            "set knee 0.1",
            "set swing_hip NaN",
            "set swing_hip inf",
            "set swing_hip -inf",
            "set swing_hip 1e400",
            "set swing_hip 1.0001",
            "set swing_hip -2",
            "set swing_hip 0x10",
            "set swing_hip ½",
            "\u{0}\u{ffff}",
        ] {
            let e = Command::parse(bad, &p).expect_err(bad);
            assert!(!e.is_empty() && e.len() < 200, "{bad:?} gave {e:?}");
        }
        let huge = format!("set swing_hip {}", "9".repeat(1 << 20));
        assert!(Command::parse(&huge, &p).unwrap_err().contains("longer than"));
        // A long name is cut in the message, on a character boundary.
        let long = format!("set {} 0", "é".repeat(100));
        let e = Command::parse(&long, &p).unwrap_err();
        assert!(e.starts_with("unknown parameter") && e.len() < 120, "{e}");
    }

    #[test]
    fn a_slow_page_drops_frames_and_never_blocks_the_run() {
        let (mut tx, rx) = frame_channel();
        let frame = |index| Frame { index, time_s: 0.0, positions: vec![0.0; 3] };
        let queued = (0..FRAME_QUEUE + 5).filter(|&k| tx.offer(frame(k))).count();
        assert_eq!(queued, FRAME_QUEUE);
        assert_eq!(tx.dropped(), 5);
        // The page reads the oldest frames first; the run keeps going after the page has gone.
        let mut rx = rx;
        assert_eq!(rx.0.blocking_recv().unwrap().index, 0);
        drop(rx);
        assert!(!tx.offer(frame(99)));
        assert_eq!(tx.dropped(), 6);
    }

    #[test]
    fn commands_wait_for_the_next_control_step() {
        let (tx, rx) = command_channel();
        for _ in 0..COMMAND_QUEUE {
            tx.send(Command::Step).unwrap();
        }
        assert!(tx.send(Command::Pause).unwrap_err().contains("try again"));
        assert_eq!(rx.drain().count(), COMMAND_QUEUE);
        assert_eq!(rx.drain().count(), 0);
        drop(rx);
        assert_eq!(tx.send(Command::Resume).unwrap_err(), "the run has ended");
    }
}
