//! A torque delay removed while a log streams: chunk by chunk, the rows
//! and torques [`aras_signal::delay_torque`] gives for the whole log.

use aras_log::Columns;

/// The shift of [`aras_signal::delay_torque`] over a stream of rows: rows
/// are emitted once the torque they take has been read; the rows without
/// such a torque (the last `⌈d⌉`, or the first `⌈−d⌉`) are never emitted.
pub(crate) struct TorqueShift {
    delay: f64,
    /// `⌊d⌋`, and the rows after a row that its torque reads.
    whole: i64,
    ahead: i64,
    /// Rows read but still needed (emitting, or as history), from global
    /// row `start`: the rows read so far are `start + buf.len()`.
    buf: Columns,
    start: usize,
    /// Next global row to emit.
    next: usize,
}

impl TorqueShift {
    pub(crate) fn new(delay: f64) -> Self {
        let whole = delay.floor() as i64;
        Self {
            delay,
            whole,
            ahead: whole + i64::from(delay != delay.floor()),
            buf: Columns::default(),
            start: 0,
            next: (-whole).max(0) as usize,
        }
    }

    /// Takes the rows `input` (the log's next ones) and appends to `out`
    /// every row whose torque is now known; returns how many.
    pub(crate) fn push(&mut self, input: &Columns, out: &mut Columns) -> usize {
        super::log::append(&mut self.buf, input);
        // Row i is ready when row i + ahead has been read.
        let read = self.start + self.buf.len();
        let end = (read as i64 - self.ahead.max(0)).max(self.next as i64) as usize;
        let rows = self.next - self.start..end - self.start;
        if rows.is_empty() {
            // Nothing ready (before the first rows a negative delay skips,
            // `next` may lie past the rows read).
            return 0;
        }
        let at = out.len();
        super::log::append_rows(out, &self.buf, rows.clone());
        for k in 0..out.joints() {
            for (o, i) in out.tau[k][at..].iter_mut().zip(rows.clone()) {
                *o = aras_signal::delayed_at(&self.buf.tau[k], i, self.delay);
            }
        }
        self.next = end;
        // Keep the rows a later row's torque still reads (and the next
        // rows to emit).
        let keep_from = (self.next as i64 + self.whole.min(0)).max(self.start as i64) as usize;
        super::log::drain_front(&mut self.buf, keep_from - self.start);
        self.start = keep_from;
        rows.len()
    }
}
