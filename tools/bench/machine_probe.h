/* machine_probe.h — what this machine can do, measured in the same run as the benchmark:
 * STREAM triad bandwidth and fp32 FMA peak, both with `threads` threads, and what a cache line costs
 * between two threads. */
#ifndef GLOW_MACHINE_PROBE_H
#define GLOW_MACHINE_PROBE_H
#include <stddef.h>
#include <stdint.h>

/* STREAM triad a[i] = b[i] + s*c[i] over three arrays of `doubles` doubles each (choose >= 4x the
 * last-level cache), `reps` repetitions, best time; bytes counted the STREAM way (3 x 8 per element,
 * no write-allocate). Returns GB/s (1e9 bytes), or a negative value when out of memory. */
double glow_probe_stream_triad(uint32_t threads, size_t doubles, uint32_t reps);

/* fp32 FMA peak: each thread runs independent 8-wide FMA chains (AVX2+FMA where the CPU has it,
 * else the compiler's best) for about `ms` milliseconds. Returns GFLOP/s (an FMA = 2 FLOPs) and
 * the instruction set used in *isa. */
double glow_probe_fma_peak(uint32_t threads, double ms, const char **isa);

/* Core-to-core latency: two threads hand a cache line back and forth `rounds` times (each waits for
 * the other's store, then stores); returns the mean round trip in ns (two one-way transfers), the
 * best of 3 runs, or a negative value when a thread cannot start. What a stage pays per line that
 * the other core wrote last (runtime/src/pool.c's shares keep work on its core for that reason).
 * The threads are not pinned: the OS places them, as it places the runtime's workers. */
double glow_probe_line_round_trip(uint32_t rounds);

#endif
