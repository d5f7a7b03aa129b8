//! Progress of long runs (style, render) on stderr: a bar on a terminal, or plain lines with an
//! ETA for farm and CI logs, where a bar's carriage returns would be noise (`--progress log`).
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How a long run reports its progress.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProgressMode {
    /// Nothing.
    #[default]
    Off,
    /// An indicatif bar (drawn only when stderr is a terminal).
    Bar,
    /// One plain line per tenth of the certain work (a settle's budget is not: it may end early),
    /// and at least every [`LOG_INTERVAL`] in between.
    Log,
}

/// The longest a log goes without a progress line while work advances.
pub const LOG_INTERVAL: Duration = Duration::from_secs(30);

/// Progress through `total` units of work.
pub struct Progress {
    label: &'static str,
    bar: Option<indicatif::ProgressBar>,
    log: Option<Mutex<LogState>>,
}

struct LogState {
    total: u64,
    done: u64,
    /// Units of the work left that are only an upper bound: a settle's budget, which the settle
    /// ends early once it reaches rest (the demo's settle is budgeted 32,400 steps and takes about
    /// 5,200; counted as certain, the ETA read 4 minutes for a 25 s run).
    open: u64,
    message: String,
    start: Instant,
    last_line: Instant,
    /// The tenths of the work already logged.
    tenths_logged: u64,
    /// Progress lines written.
    lines: u64,
}

impl Progress {
    /// Progress labelled `label` (e.g. "style") in the given mode.
    pub fn new(mode: ProgressMode, label: &'static str, total: u64) -> Progress {
        let bar = (mode == ProgressMode::Bar).then(|| {
            let bar = indicatif::ProgressBar::new(total);
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({elapsed}<{eta})")
            {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        });
        let now = Instant::now();
        let log = (mode == ProgressMode::Log).then(|| {
            Mutex::new(LogState {
                total,
                done: 0,
                open: 0,
                message: String::new(),
                start: now,
                last_line: now,
                tenths_logged: 0,
                lines: 0,
            })
        });
        Progress { label, bar, log }
    }

    /// Names the part of the work under way (a stage).
    pub fn set_message(&self, message: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(message.to_owned());
        }
        if let Some(log) = &self.log {
            lock(log).message = message.to_owned();
        }
    }

    /// Sets the total (work found to be larger or smaller than planned).
    pub fn set_total(&self, total: u64) {
        if let Some(bar) = &self.bar {
            bar.set_length(total);
        }
        if let Some(log) = &self.log {
            lock(log).total = total;
        }
    }

    /// Marks `units` of the work left as an upper bound only (see [`Self::inc_open`]).
    pub fn add_open(&self, units: u64) {
        if let Some(log) = &self.log {
            lock(log).open += units;
        }
    }

    /// Records `units` of the open work done, or found not needed (the rest of a budget).
    pub fn inc_open(&self, units: u64) {
        self.add(units, units);
    }

    /// Records `units` more units of work done.
    pub fn inc(&self, units: u64) {
        self.add(units, 0);
    }

    /// `units` more done, `open` of them from the open work.
    fn add(&self, units: u64, open: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(units);
        }
        if let Some(log) = &self.log {
            let mut state = lock(log);
            state.open = state.open.saturating_sub(open);
            let done = state.done + units;
            self.advance(&mut state, done);
        }
    }

    /// Records that `done` units of work are done in all.
    pub fn set_done(&self, done: u64) {
        if let Some(bar) = &self.bar {
            bar.set_position(done);
        }
        if let Some(log) = &self.log {
            let mut state = lock(log);
            if done > state.done {
                self.advance(&mut state, done);
            }
        }
    }

    /// Ends the progress: clears the bar, or logs the total time.
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
        if let Some(log) = self.log {
            let state = log.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner());
            eprintln!("{}: done in {}", self.label, clock(state.start.elapsed()));
        }
    }

    fn advance(&self, state: &mut LogState, done: u64) {
        let before = state.done;
        state.done = done.min(state.total);
        let finished = state.done == state.total && before < state.total;
        // Tenths of the certain work: a settle's budget would hold the lines back until it ended.
        let certain = state.total - state.open_left();
        let tenths = (state.done * 10).checked_div(certain).unwrap_or(10);
        let now = Instant::now();
        if tenths > state.tenths_logged || finished || now - state.last_line >= LOG_INTERVAL {
            state.tenths_logged = state.tenths_logged.max(tenths);
            state.last_line = now;
            state.lines += 1;
            eprintln!("{}", line(self.label, state, now - state.start));
        }
    }
}

impl LogState {
    /// The open work among the work left (a settle may have run past its budget).
    fn open_left(&self) -> u64 {
        self.open.min(self.total.saturating_sub(self.done))
    }
}

fn lock(log: &Mutex<LogState>) -> std::sync::MutexGuard<'_, LogState> {
    // A panic elsewhere while holding the lock leaves counters that are still valid.
    log.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// `style: 40% (1200/3000) press, elapsed 0:42, eta 1:03`, or with open work left,
/// `eta 0:20 to 4:15`: the certain work left, then all of it.
fn line(label: &str, state: &LogState, elapsed: Duration) -> String {
    let fraction = if state.total == 0 { 1.0 } else { state.done as f64 / state.total as f64 };
    let (left, open) = (state.total.saturating_sub(state.done), state.open_left());
    let time_for = |units: u64| clock(elapsed.mul_f64(units as f64 / state.done as f64));
    let eta = match (state.done, open) {
        (0, _) => "?".to_owned(),
        (_, 0) => time_for(left),
        _ => format!("{} to {}", time_for(left - open), time_for(left)),
    };
    let message = if state.message.is_empty() { String::new() } else { format!(" {}", state.message) };
    format!(
        "{label}: {:.0}% ({}/{}){message}, elapsed {}, eta {eta}",
        100.0 * fraction,
        state.done,
        state.total,
        clock(elapsed)
    )
}

/// `h:mm:ss`, or `m:ss` under an hour.
fn clock(duration: Duration) -> String {
    let seconds = duration.as_secs();
    let (h, m, s) = (seconds / 3600, seconds / 60 % 60, seconds % 60);
    if h > 0 {
        format!("{h}:{m:02}:{s:02}")
    } else {
        format!("{m}:{s:02}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(total: u64, done: u64) -> LogState {
        let now = Instant::now();
        LogState {
            total,
            done,
            open: 0,
            message: "press".into(),
            start: now,
            last_line: now,
            tenths_logged: 0,
            lines: 0,
        }
    }

    #[test]
    fn the_eta_extrapolates_the_rate_so_far() {
        let text = line("style", &state(400, 100), Duration::from_secs(30));
        assert_eq!(text, "style: 25% (100/400) press, elapsed 0:30, eta 1:30");
        let text = line("style", &state(10, 0), Duration::from_secs(3));
        assert_eq!(text, "style: 0% (0/10) press, elapsed 0:03, eta ?");
    }

    #[test]
    fn open_work_gives_the_eta_as_a_range() {
        // 100 of 1,000 done in 10 s; 800 of the 900 left are a settle's budget.
        let mut state = state(1000, 100);
        state.open = 800;
        let text = line("style", &state, Duration::from_secs(10));
        assert_eq!(text, "style: 10% (100/1000) press, elapsed 0:10, eta 0:10 to 1:30");
        // The settle under way with nothing certain left: it may end at once.
        state.done = 400;
        state.open = 600;
        let text = line("style", &state, Duration::from_secs(40));
        assert_eq!(text, "style: 40% (400/1000) press, elapsed 0:40, eta 0:00 to 1:00");
    }

    #[test]
    fn a_settle_ending_early_closes_the_range() {
        let progress = Progress::new(ProgressMode::Log, "test", 1000);
        progress.add_open(900);
        for _ in 0..100 {
            progress.inc(1);
        }
        progress.inc_open(50);
        progress.inc_open(850); // rest: the settle converged
        let state = lock(progress.log.as_ref().unwrap());
        assert_eq!((state.done, state.open), (1000, 0));
        // A line per tenth of the certain 100 (not of the 1,000), then the settle's steps wait for
        // the interval, and its end gives the last.
        assert_eq!((state.lines, state.tenths_logged), (11, 10));
    }

    #[test]
    fn clocks_read_as_minutes_then_hours() {
        assert_eq!(clock(Duration::from_secs(59)), "0:59");
        assert_eq!(clock(Duration::from_secs(3 * 3600 + 5 * 60 + 7)), "3:05:07");
    }

    #[test]
    fn a_log_gets_one_line_per_tenth_however_fine_the_steps() {
        let progress = Progress::new(ProgressMode::Log, "test", 1000);
        for _ in 0..1000 {
            progress.inc(1);
        }
        let state = lock(progress.log.as_ref().unwrap());
        assert_eq!((state.lines, state.tenths_logged, state.done), (10, 10, 1000));
    }
}
