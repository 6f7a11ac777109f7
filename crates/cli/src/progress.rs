//! The progress bar of `anima run` and `anima optimise`: shown only on a terminal, updated in steps the
//! runs choose so that it costs nothing measurable; warnings printed above it.

use anima_run::run::Progress;

/// An indicatif bar, or nothing when standard error is not a terminal or `--quiet` is given (warnings
/// are printed either way unless quiet).
#[derive(Debug)]
pub struct Bar {
    bar: Option<indicatif::ProgressBar>,
    show: bool,
    quiet: bool,
}

impl Bar {
    pub fn new(report: bool) -> Self {
        let show = report && std::io::IsTerminal::is_terminal(&std::io::stderr());
        Self { bar: None, show, quiet: !report }
    }
}

impl Progress for Bar {
    fn begin(&mut self, total: u64) {
        if self.show {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} ({eta} left)",
                )
                .expect("a valid template"),
            );
            self.bar = Some(bar);
        }
    }

    fn advance(&mut self, done: u64) {
        if let Some(bar) = &self.bar {
            bar.set_position(done);
        }
    }

    fn warn(&mut self, message: &str) {
        if self.quiet {
            return;
        }
        match &self.bar {
            Some(bar) => bar.println(format!("anima: warning: {message}")),
            None => eprintln!("anima: warning: {message}"),
        }
    }

    fn end(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
