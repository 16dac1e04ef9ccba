//! Allocations that fail end the process with a message and exit 1: those of the Rust code
//! (the global allocator below) and those of the C libraries linked in (libhdf5, the
//! `hdf5` crate's strings), whose `malloc`, `calloc` and `realloc` are these functions,
//! forwarding to the C library's own. A C caller that does not check for a null pointer
//! (`VarLenUnicode`'s copy of a string into memory it did not get) would otherwise crash
//! with SIGSEGV under a memory limit (ulimit -v, a cgroup's memory.max). The archive's
//! writer no longer makes such strings (its strings are fixed-length, their bytes in Rust
//! memory); the reader still does for archives written before, and libhdf5 allocates its
//! own buffers (chunks, metadata) through these functions.

use std::io::Write;
use std::sync::atomic::{AtomicI64, Ordering};

/// Allocations from this size on remove the run's unfinished staging folder before the
/// process ends (small ones are likely the cleanup's own, which would fail again).
pub const LARGE: usize = 1 << 20;

/// The thread that is ending the process (0: none).
static ENDING: AtomicI64 = AtomicI64::new(0);

unsafe extern "C" {
    /// `_exit(2)`: ends the process at once (no atexit handlers, no flushing).
    #[link_name = "_exit"]
    fn exit_now(code: i32) -> !;
    fn gettid() -> i32;
    fn __libc_malloc(size: usize) -> *mut core::ffi::c_void;
    fn __libc_calloc(n: usize, size: usize) -> *mut core::ffi::c_void;
    fn __libc_realloc(p: *mut core::ffi::c_void, size: usize) -> *mut core::ffi::c_void;
}

const MESSAGE: &[u8] = b"sgbem: out of memory: an allocation of the run failed (a memory \
    limit: ulimit -v, the cgroup's memory.max of a container or SLURM job); the output folder \
    was left as it was: coarsen the mesh, or raise the limit (`sgbem check` prints the memory \
    a run needs)\n";

/// Ends the process after a failed allocation of `size` bytes, unless the estimate is
/// probing what the system grants (then the caller gets the null pointer). Nothing here may
/// need memory it cannot do without: a failure while ending ends at once.
pub fn allocation_failed(size: usize) {
    if sgbem::estimate::PROBING.load(Ordering::SeqCst) {
        return;
    }
    // SAFETY: gettid has no preconditions.
    let me = i64::from(unsafe { gettid() });
    if let Err(holder) = ENDING.compare_exchange(0, me, Ordering::SeqCst, Ordering::SeqCst) {
        if holder == me {
            // The cleanup itself ran out: end without it.
            let _ = std::io::stderr().write_all(MESSAGE);
            // SAFETY: _exit has no preconditions.
            unsafe { exit_now(1) }
        }
        // Another thread is ending the process: wait for it (returning would abort).
        loop {
            std::thread::sleep(std::time::Duration::from_secs(1));
        }
    }
    if size >= LARGE {
        sgbem::output::folder::remove_unfinished();
    }
    let _ = std::io::stderr().write_all(MESSAGE);
    // Other threads may still be allocating: end without running anything more.
    // SAFETY: _exit has no preconditions.
    unsafe { exit_now(1) }
}

/// The C library's `malloc` for every caller in the process, a failure ending it.
///
/// # Safety
/// As `malloc(3)`.
#[no_mangle]
pub unsafe extern "C" fn malloc(size: usize) -> *mut core::ffi::c_void {
    let p = unsafe { __libc_malloc(size) };
    if p.is_null() && size > 0 {
        allocation_failed(size);
    }
    p
}

/// The C library's `calloc` for every caller in the process, a failure ending it.
///
/// # Safety
/// As `calloc(3)`.
#[no_mangle]
pub unsafe extern "C" fn calloc(n: usize, size: usize) -> *mut core::ffi::c_void {
    let p = unsafe { __libc_calloc(n, size) };
    if p.is_null() && n > 0 && size > 0 {
        allocation_failed(n.saturating_mul(size));
    }
    p
}

/// The C library's `realloc` for every caller in the process, a failure ending it.
///
/// # Safety
/// As `realloc(3)`.
#[no_mangle]
pub unsafe extern "C" fn realloc(
    ptr: *mut core::ffi::c_void,
    size: usize,
) -> *mut core::ffi::c_void {
    let p = unsafe { __libc_realloc(ptr, size) };
    if p.is_null() && size > 0 {
        allocation_failed(size);
    }
    p
}

/// The system allocator, except that a failed allocation ends the process with a message
/// and exit 1 instead of the abort (exit 134) or the library panic (exit 101) it would be.
struct Guarded;

// SAFETY: every call is forwarded to the system allocator with its own arguments.
unsafe impl std::alloc::GlobalAlloc for Guarded {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc(layout) };
        if p.is_null() {
            allocation_failed(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        if p.is_null() {
            allocation_failed(layout.size());
        }
        p
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        let p = unsafe { std::alloc::System.realloc(ptr, layout, size) };
        if p.is_null() {
            allocation_failed(size);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Guarded = Guarded;
