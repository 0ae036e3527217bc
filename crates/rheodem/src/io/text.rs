//! Large text outputs formatted in parallel: the lines of a table are written in blocks on
//! rayon's pool and joined in order, so the text does not depend on the thread count.

use rayon::prelude::*;

/// Items formatted per block: large enough that a block's work outweighs its hand-over.
const BLOCK: usize = 2048;

/// Appends to `out` the text `line` writes for each item, in the items' order. The blocks
/// of items are formatted on rayon's pool (of the calling context), then appended in order.
pub fn append_lines<T: Sync>(out: &mut String, items: &[T], line: impl Fn(&mut String, &T) + Sync) {
    let blocks: Vec<String> = items
        .par_chunks(BLOCK)
        .map(|block| {
            let mut s = String::new();
            for item in block {
                line(&mut s, item);
            }
            s
        })
        .collect();
    out.reserve(blocks.iter().map(String::len).sum());
    for b in &blocks {
        out.push_str(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fmt::Write;

    #[test]
    fn lines_keep_the_items_order_across_blocks() {
        let items: Vec<usize> = (0..3 * BLOCK + 5).collect();
        let mut out = String::from("head\n");
        append_lines(&mut out, &items, |s, k| {
            let _ = writeln!(s, "{k}");
        });
        let expected: String = std::iter::once("head".to_string())
            .chain(items.iter().map(usize::to_string))
            .map(|l| l + "\n")
            .collect();
        assert_eq!(out, expected);
    }
}
