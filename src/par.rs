//! Data parallelism: rayon on the desktop and the command line; in a browser (wasm32-unknown-unknown,
//! one thread) the same calls run in order on the page's thread, and rayon is not in the module.
//!
//! Every parallel loop of the engine writes `use crate::par::prelude::*` and `crate::par::join`
//! instead of naming rayon. In the browser, rayon had a pool of one thread, which still split each
//! loop once and ran the halves one after the other; its code (its bridges, producers and
//! consumers, instantiated for every loop) was ~190 KB of the module. The sequential versions keep
//! rayon's signatures (`reduce(identity, op)`, `fold` yielding the accumulators, `for_each_init`),
//! so the engine's code is one text for both; the wasm32 clippy of `.ci/run` compiles them, and the
//! browser test checks the browser's calibration against the native one.

#[cfg(not(target_arch = "wasm32"))]
pub use rayon::{
    Scope, current_num_threads, current_thread_index, in_place_scope, join, prelude, scope,
};

#[cfg(target_arch = "wasm32")]
pub use sequential::*;

#[cfg(target_arch = "wasm32")]
mod sequential {
    /// `rayon::join`: `a`, then `b`.
    pub fn join<A, B, RA, RB>(a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB,
    {
        let ra = a();
        (ra, b())
    }

    /// One thread.
    pub fn current_num_threads() -> usize {
        1
    }

    /// Never a pool's thread.
    pub fn current_thread_index() -> Option<usize> {
        None
    }

    /// `rayon::Scope`: a spawned job runs at once.
    pub struct Scope<'scope>(std::marker::PhantomData<&'scope ()>);

    impl<'scope> Scope<'scope> {
        pub fn spawn<F: FnOnce(&Scope<'scope>) + 'scope>(&self, job: F) {
            job(self)
        }
    }

    /// `rayon::scope`.
    pub fn scope<'scope, F: FnOnce(&Scope<'scope>) -> R, R>(f: F) -> R {
        f(&Scope(std::marker::PhantomData))
    }

    /// `rayon::in_place_scope`.
    pub fn in_place_scope<'scope, F: FnOnce(&Scope<'scope>) -> R, R>(f: F) -> R {
        scope(f)
    }

    pub mod prelude {
        /// A "parallel" iterator: an iterator run in order, with rayon's adapters.
        #[must_use = "iterators do nothing unless consumed"]
        pub struct Seq<I>(I);

        /// `rayon::iter::IntoParallelIterator`.
        pub trait IntoParallelIterator {
            type Iter: Iterator<Item = Self::Item>;
            type Item;
            fn into_par_iter(self) -> Seq<Self::Iter>;
        }

        impl<C: IntoIterator> IntoParallelIterator for C {
            type Iter = C::IntoIter;
            type Item = C::Item;
            fn into_par_iter(self) -> Seq<C::IntoIter> {
                Seq(self.into_iter())
            }
        }

        /// `rayon::iter::IntoParallelRefIterator`.
        pub trait IntoParallelRefIterator<'data> {
            type Iter: Iterator;
            fn par_iter(&'data self) -> Seq<Self::Iter>;
        }

        impl<'data, C: ?Sized + 'data> IntoParallelRefIterator<'data> for C
        where
            &'data C: IntoIterator,
        {
            type Iter = <&'data C as IntoIterator>::IntoIter;
            fn par_iter(&'data self) -> Seq<Self::Iter> {
                Seq(self.into_iter())
            }
        }

        /// `rayon::iter::IntoParallelRefMutIterator`.
        pub trait IntoParallelRefMutIterator<'data> {
            type Iter: Iterator;
            fn par_iter_mut(&'data mut self) -> Seq<Self::Iter>;
        }

        impl<'data, C: ?Sized + 'data> IntoParallelRefMutIterator<'data> for C
        where
            &'data mut C: IntoIterator,
        {
            type Iter = <&'data mut C as IntoIterator>::IntoIter;
            fn par_iter_mut(&'data mut self) -> Seq<Self::Iter> {
                Seq(self.into_iter())
            }
        }

        /// `rayon::slice::ParallelSlice`.
        pub trait ParallelSlice<T> {
            fn par_chunks(&self, size: usize) -> Seq<std::slice::Chunks<'_, T>>;
            fn par_chunks_exact(&self, size: usize) -> Seq<std::slice::ChunksExact<'_, T>>;
        }

        impl<T> ParallelSlice<T> for [T] {
            fn par_chunks(&self, size: usize) -> Seq<std::slice::Chunks<'_, T>> {
                Seq(self.chunks(size))
            }
            fn par_chunks_exact(&self, size: usize) -> Seq<std::slice::ChunksExact<'_, T>> {
                Seq(self.chunks_exact(size))
            }
        }

        /// `rayon::slice::ParallelSliceMut`.
        pub trait ParallelSliceMut<T> {
            fn par_chunks_mut(&mut self, size: usize) -> Seq<std::slice::ChunksMut<'_, T>>;
        }

        impl<T> ParallelSliceMut<T> for [T] {
            fn par_chunks_mut(&mut self, size: usize) -> Seq<std::slice::ChunksMut<'_, T>> {
                Seq(self.chunks_mut(size))
            }
        }

        impl<I: Iterator> IntoIterator for Seq<I> {
            type Item = I::Item;
            type IntoIter = I;
            fn into_iter(self) -> I {
                self.0
            }
        }

        impl<I: Iterator> Seq<I> {
            pub fn map<R, F: FnMut(I::Item) -> R>(self, f: F) -> Seq<std::iter::Map<I, F>> {
                Seq(self.0.map(f))
            }
            pub fn filter<F: FnMut(&I::Item) -> bool>(self, f: F) -> Seq<std::iter::Filter<I, F>> {
                Seq(self.0.filter(f))
            }
            pub fn filter_map<R, F: FnMut(I::Item) -> Option<R>>(
                self,
                f: F,
            ) -> Seq<std::iter::FilterMap<I, F>> {
                Seq(self.0.filter_map(f))
            }
            pub fn enumerate(self) -> Seq<std::iter::Enumerate<I>> {
                Seq(self.0.enumerate())
            }
            pub fn zip<Z: IntoParallelIterator>(self, other: Z) -> Seq<std::iter::Zip<I, Z::Iter>> {
                Seq(self.0.zip(other.into_par_iter().0))
            }
            pub fn chain<Z: IntoParallelIterator<Item = I::Item>>(
                self,
                other: Z,
            ) -> Seq<std::iter::Chain<I, Z::Iter>> {
                Seq(self.0.chain(other.into_par_iter().0))
            }
            pub fn copied<'a, T: 'a + Copy>(self) -> Seq<std::iter::Copied<I>>
            where
                I: Iterator<Item = &'a T>,
            {
                Seq(self.0.copied())
            }
            /// `flat_map_iter`: each item's iterator, in order.
            pub fn flat_map_iter<U: IntoIterator, F: FnMut(I::Item) -> U>(
                self,
                f: F,
            ) -> Seq<std::iter::FlatMap<I, U, F>> {
                Seq(self.0.flat_map(f))
            }
            /// `chunks`: the items in vectors of `size` (the last one shorter).
            pub fn chunks(self, size: usize) -> Seq<impl Iterator<Item = Vec<I::Item>>> {
                assert!(size != 0, "chunk size must not be zero");
                let mut items = self.0;
                Seq(std::iter::from_fn(move || {
                    let chunk: Vec<I::Item> = items.by_ref().take(size).collect();
                    (!chunk.is_empty()).then_some(chunk)
                }))
            }
            /// No splitting to bound.
            pub fn with_min_len(self, _min: usize) -> Self {
                self
            }
            /// `map_init`: one state for the whole loop (rayon makes one per piece of work).
            pub fn map_init<S, R>(
                self,
                init: impl FnOnce() -> S,
                mut f: impl FnMut(&mut S, I::Item) -> R,
            ) -> Seq<impl Iterator<Item = R>> {
                let mut state = init();
                Seq(self.0.map(move |item| f(&mut state, item)))
            }
            pub fn for_each<F: FnMut(I::Item)>(self, f: F) {
                self.0.for_each(f)
            }
            /// `for_each_init`: one state for the whole loop.
            pub fn for_each_init<S>(
                self,
                init: impl FnOnce() -> S,
                mut f: impl FnMut(&mut S, I::Item),
            ) {
                let mut state = init();
                self.0.for_each(|item| f(&mut state, item))
            }
            /// rayon's `fold`: the accumulators of the pieces of work — here one.
            pub fn fold<T>(
                self,
                identity: impl FnOnce() -> T,
                op: impl FnMut(T, I::Item) -> T,
            ) -> Seq<std::iter::Once<T>> {
                Seq(std::iter::once(self.0.fold(identity(), op)))
            }
            /// rayon's `reduce`: from `identity()`, the items combined in order.
            pub fn reduce(
                self,
                identity: impl FnOnce() -> I::Item,
                op: impl FnMut(I::Item, I::Item) -> I::Item,
            ) -> I::Item {
                self.0.fold(identity(), op)
            }
            pub fn sum<S: std::iter::Sum<I::Item>>(self) -> S {
                self.0.sum()
            }
            pub fn count(self) -> usize {
                self.0.count()
            }
            pub fn collect<C: FromIterator<I::Item>>(self) -> C {
                self.0.collect()
            }
        }
    }
}
