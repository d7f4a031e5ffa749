//! Process-wide settings that the binaries apply when they start.

/// Caps glibc's malloc at 2 arenas (its default is 8 per core): each thread that allocates
/// otherwise gets an arena of its own, whose freed memory it keeps. A hybrid frame allocates
/// on the rayon workers and on the BVH's build thread at once (`Tracer::build_in_background`),
/// and their arenas' leftovers added markedly to a first frame's peak memory (the commit that
/// set this has the figures); with 2 the renderer's own buffers dominate. Allocation is rare in
/// the frame's loops, so sharing arenas costs no measurable time. Does nothing on other
/// platforms.
pub fn limit_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only changes the allocator's tuning; it is called before any thread
    // of ours is started, and glibc documents M_ARENA_MAX as settable at any time.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 2);
    }
}
