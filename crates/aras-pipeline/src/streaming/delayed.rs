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
    /// row `start`.
    buf: Columns,
    start: usize,
    /// Next global row to emit; rows read so far.
    next: usize,
    read: usize,
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
            read: 0,
        }
    }

    /// Takes the rows `input` (the log's next ones) and appends to `out`
    /// every row whose torque is now known; returns how many.
    pub(crate) fn push(&mut self, input: &Columns, out: &mut Columns) -> usize {
        super::log::append(&mut self.buf, input);
        self.read += input.len();
        // Row i is ready when row i + ahead has been read.
        let end = (self.read as i64 - self.ahead.max(0)).max(0) as usize;
        let mut emitted = 0;
        while self.next < end {
            let i = self.next - self.start;
            out.t.push(self.buf.t[i]);
            for k in 0..2 {
                out.theta[k].push(self.buf.theta[k][i]);
                let tau = aras_signal::delayed_at(&self.buf.tau[k], i, self.delay);
                out.tau[k].push(tau);
                for (o, b) in [
                    (&mut out.theta_dot[k], &self.buf.theta_dot[k]),
                    (&mut out.theta_ddot[k], &self.buf.theta_ddot[k]),
                ] {
                    if let Some(v) = b.get(i) {
                        o.push(*v);
                    }
                }
            }
            self.next += 1;
            emitted += 1;
        }
        // Keep the rows a later row's torque still reads (and the next
        // rows to emit).
        let keep_from = (self.next as i64 + self.whole.min(0)).max(self.start as i64) as usize;
        super::log::drain_front(&mut self.buf, keep_from - self.start);
        self.start = keep_from;
        emitted
    }
}
