//! Independent work (the folds of a cross-validation, stretches of samples, the cut-offs an
//! identification tries) spread over the machine's cores.

/// `f` of every item, in the items' order, on up to as many threads as the machine has
/// cores (contiguous chunks, one per thread). A panic in `f` is raised again here.
pub fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(items.len());
    if threads <= 1 {
        return items.iter().map(f).collect();
    }
    let chunk = items.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks(chunk)
            .map(|part| {
                let f = &f;
                scope.spawn(move || part.iter().map(f).collect::<Vec<R>>())
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| match h.join() {
                Ok(results) => results,
                Err(panic) => std::panic::resume_unwind(panic),
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_order_of_the_items() {
        let items: Vec<usize> = (0..37).collect();
        let squares = parallel_map(&items, |&k| k * k);
        assert_eq!(squares, items.iter().map(|k| k * k).collect::<Vec<_>>());
        assert!(parallel_map(&[] as &[usize], |&k| k).is_empty());
    }
}
