//! The ordered multi-input merge (DESIGN §6, §7). A consumer with several inputs
//! processes their messages in stamp order, whatever order the scheduler
//! delivered them in, so that `sim` runs are bit-identical.
//!
//! Each input carries a watermark: its publisher has nothing earlier than the
//! watermark still to send (the stamp of its last message, or of an explicit
//! progress message). The next message (smallest stamp, ties by input index) is
//! released only when no other input can still produce one that sorts before it.

use std::collections::VecDeque;

#[derive(Debug)]
struct Input<T> {
    queue: VecDeque<(u64, T)>,
    watermark: Option<u64>,
    ended: bool,
}

/// Merges N input streams by stamp.
#[derive(Debug)]
pub struct OrderedMerge<T> {
    inputs: Vec<Input<T>>,
    /// Each input's stamps strictly increase: after a message stamped `s`
    /// nothing at `s` can follow, so the watermark becomes `s + 1`.
    strict: bool,
}

/// A message pushed out of order on one input (its stamp is below that input's
/// watermark): the caller rejects it instead of breaking the order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("input {input}: stamp {stamp_ns} is before its watermark {watermark_ns}")]
pub struct OutOfOrder {
    /// Input index.
    pub input: usize,
    /// The message's stamp.
    pub stamp_ns: u64,
    /// The input's watermark.
    pub watermark_ns: u64,
}

impl<T> OrderedMerge<T> {
    /// A merge over `n` inputs.
    pub fn new(n: usize) -> Self {
        OrderedMerge {
            inputs: (0..n)
                .map(|_| Input {
                    queue: VecDeque::new(),
                    watermark: None,
                    ended: false,
                })
                .collect(),
            strict: false,
        }
    }

    /// A merge over `n` inputs whose stamps strictly increase on each input
    /// (the estimator shell refuses a repeated stamp before it gets here): a
    /// message stamped `s` advances its input's watermark past `s`, so another
    /// input's message at `s` is released without waiting for the next one.
    pub fn strictly_increasing(n: usize) -> Self {
        OrderedMerge {
            strict: true,
            ..Self::new(n)
        }
    }

    /// Queues a message of `input`; its stamp becomes the input's watermark.
    pub fn push(&mut self, input: usize, stamp_ns: u64, item: T) -> Result<(), OutOfOrder> {
        let inp = &mut self.inputs[input];
        if let Some(w) = inp.watermark
            && stamp_ns < w
        {
            return Err(OutOfOrder {
                input,
                stamp_ns,
                watermark_ns: w,
            });
        }
        let mark = if self.strict {
            stamp_ns.saturating_add(1)
        } else {
            stamp_ns
        };
        inp.watermark = Some(inp.watermark.map_or(mark, |w| w.max(mark)));
        inp.queue.push_back((stamp_ns, item));
        Ok(())
    }

    /// Advances the watermark of `input` (a progress message): nothing earlier
    /// than `stamp_ns` will come from it.
    pub fn advance(&mut self, input: usize, stamp_ns: u64) {
        let inp = &mut self.inputs[input];
        inp.watermark = Some(inp.watermark.map_or(stamp_ns, |w| w.max(stamp_ns)));
    }

    /// Marks `input` as ended: it sends nothing more.
    pub fn end(&mut self, input: usize) {
        self.inputs[input].ended = true;
    }

    /// True when `input` has ended.
    pub fn is_ended(&self, input: usize) -> bool {
        self.inputs[input].ended
    }

    /// True when every input has ended and every queue is empty.
    pub fn is_finished(&self) -> bool {
        self.inputs.iter().all(|i| i.ended && i.queue.is_empty())
    }

    /// The earliest stamp `input` can still deliver: the head of its queue,
    /// else its watermark (`None` before it has one); `u64::MAX` once it has
    /// ended and is drained.
    pub fn next_bound(&self, input: usize) -> Option<u64> {
        let inp = &self.inputs[input];
        match inp.queue.front() {
            Some((s, _)) => Some(*s),
            None if inp.ended => Some(u64::MAX),
            None => inp.watermark,
        }
    }

    /// Messages queued in all inputs.
    pub fn queued(&self) -> usize {
        self.inputs.iter().map(|i| i.queue.len()).sum()
    }

    /// The next message in (stamp, input) order, if it is safe to release.
    pub fn pop(&mut self) -> Option<(usize, u64, T)> {
        let (idx, stamp) = self
            .inputs
            .iter()
            .enumerate()
            .filter_map(|(i, inp)| inp.queue.front().map(|(s, _)| (i, *s)))
            .min_by_key(|&(i, s)| (s, i))?;
        let safe = self.inputs.iter().enumerate().all(|(j, inp)| {
            if j == idx || inp.ended || !inp.queue.is_empty() {
                // A non-empty queue's head already sorts after the candidate.
                return true;
            }
            match inp.watermark {
                // An input before `idx` may still send this very stamp, which
                // would sort first; one after it may not send anything earlier.
                Some(w) if j < idx => w > stamp,
                Some(w) => w >= stamp,
                None => false,
            }
        });
        if !safe {
            return None;
        }
        let (s, item) = self.inputs[idx].queue.pop_front()?;
        Some((idx, s, item))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn streams() -> (Vec<u64>, Vec<u64>) {
        // Two 100 Hz / 30 Hz-ish streams with shared stamps.
        let a: Vec<u64> = (0..50).map(|k| k * 10).collect();
        let b: Vec<u64> = (0..17).map(|k| k * 30).collect();
        (a, b)
    }

    fn expected(a: &[u64], b: &[u64]) -> Vec<(usize, u64)> {
        let mut all: Vec<(u64, usize)> = a
            .iter()
            .map(|&s| (s, 0))
            .chain(b.iter().map(|&s| (s, 1)))
            .collect();
        all.sort();
        all.into_iter().map(|(s, i)| (i, s)).collect()
    }

    proptest! {
        /// Whatever the interleaving of arrivals, the output order is the same.
        #[test]
        fn order_independent_of_arrival(schedule in proptest::collection::vec(any::<bool>(), 0..200)) {
            let (a, b) = streams();
            let mut m = OrderedMerge::new(2);
            let (mut ia, mut ib) = (0, 0);
            let mut out = Vec::new();
            let mut step = schedule.into_iter();
            while ia < a.len() || ib < b.len() {
                let pick_a = match step.next() { Some(x) => x, None => ia < a.len() };
                if (pick_a && ia < a.len()) || ib >= b.len() {
                    m.push(0, a[ia], ()).unwrap();
                    ia += 1;
                    if ia == a.len() { m.end(0); }
                } else {
                    m.push(1, b[ib], ()).unwrap();
                    ib += 1;
                    if ib == b.len() { m.end(1); }
                }
                while let Some((i, s, ())) = m.pop() { out.push((i, s)); }
            }
            while let Some((i, s, ())) = m.pop() { out.push((i, s)); }
            prop_assert!(m.is_finished());
            prop_assert_eq!(out, expected(&a, &b));
        }
    }

    #[test]
    fn waits_for_a_silent_input_until_its_watermark() {
        let mut m = OrderedMerge::new(2);
        m.push(1, 100, "b").unwrap();
        assert!(
            m.pop().is_none(),
            "input 0 might still send something earlier"
        );
        m.advance(0, 100);
        assert!(
            m.pop().is_none(),
            "input 0 may still send stamp 100, which sorts first"
        );
        m.advance(0, 101);
        assert_eq!(m.pop(), Some((1, 100, "b")));
        assert_eq!(
            m.push(0, 50, "late"),
            Err(OutOfOrder {
                input: 0,
                stamp_ns: 50,
                watermark_ns: 101
            })
        );
    }
}
