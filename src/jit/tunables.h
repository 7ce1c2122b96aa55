// The JIT's tunables, in one table: when a site is hot, how hard to try, how big a trace may
// grow, and how often a compiled loop looks for Ctrl-C.
#pragma once

#include <cstddef>

namespace simit::jit {

// Executions of a site before it is compiled (0: compile on its first execution). The
// engine's option overrides it.
inline constexpr long kHotThreshold = 2;
// A production run (JitOptions::eager) compiles a map over a set of at least this many
// elements at its first execution, whatever the threshold (a kernel compiles in 5-80 ms;
// interpreting a map costs about 1-25 us an element).
inline constexpr long kEagerElements = 4096;
// Compilations of one site that may fail before it stays interpreted for good.
inline constexpr int kMaxFailures = 3;
// Statements a trace may hold after inlining and unrolling.
inline constexpr size_t kMaxTraceStatements = 200000;
// Components a dense tensor of a traced function may have, blocked or not: the tracer makes
// each one a value of its own (the fem Hessian's element matrix, 4 x 4 blocks of 3 x 3, has
// 144; a hexahedron's 24 x 24 element matrix 576). A larger tensor leaves its site
// interpreted.
inline constexpr size_t kMaxDenseComponents = 1024;
// Multiplications a matrix product may unroll (a 12 x 12 by 12 x 12 product has 1728). A
// larger product is tiled: its operands and result lie in per-element scratch arrays, and it
// runs as loops over kTile x kTile tiles of its result (loop_ir.h).
inline constexpr size_t kMaxUnrolledProduct = 1728;
inline constexpr int kTile = 12;
// A float tensor of more components than this that a field holds, an outer product makes or
// an element-wise operation or matrix-vector product computes from one in a scratch array (a
// tiled product's result) lies in a scratch array and is computed by a loop, not unrolled.
inline constexpr size_t kTileAbove = 144;
// Calls inlined inside one another. Simit has no recursion, so a program's call chains are
// as deep as its functions are many; the limit only keeps the tracer, which recurses a few
// frames per level, well inside a thread's stack (a few kB a level).
inline constexpr int kMaxInlineDepth = 256;
// Elements a kernel runs between two checks for an interrupt (Ctrl-C).
inline constexpr int kChunkElements = 16384;
// The smallest chunk of a map on threads (a multiple of kLanes32): a chunk's call must cost far
// more than handing it to a thread.
inline constexpr int kMinThreadChunk = 256;
// The test-only shuffled executor's chunks (jit/executor.h): a few elements, so that the
// corpus's small sets run in several chunks.
inline constexpr int kShuffledChunk = 3;
// LLVM's optimisation level for kernels (2 or 3), and for traces of more loop-IR nodes than
// kLargeTrace (fully unrolled element matrices), whose O2 compile exceeds 100 ms.
inline constexpr int kOptLevel = 2;
inline constexpr size_t kLargeTrace = 4000;
// A large trace that runs in lanes skips LLVM's IR pipeline (0): its IR already computes
// every value once and keeps no local in memory, and the pipeline took a quarter of its
// compile time for no measurable speed (the fem stiffness: 77 ms to 58).
inline constexpr int kLargeLanesTraceOptLevel = 0;
// A large trace that does not run in lanes (it calls a decomposition, or merges locals after
// a branch) skips the pipeline too, and takes LLVM's fast code generator: the fem Newton
// Hessian (20000 nodes) compiled in 220 ms at O1 with the full code generator and in 25 ms
// so, while its run time, mostly the 12 x 12 projection it calls, grew by 2%.
inline constexpr int kLargeTraceOptLevel = 0;
inline constexpr bool kLargeTraceFastCodegen = true;
// A map's matrix result is specialised to the blocks it writes (jit/specialise.h) when that
// keeps at most this fraction of them.
inline constexpr double kSpecialiseAtMost = 0.9;
// Elements a map kernel computes at once, one per SIMD lane (4 binary64 lanes: AVX2); their
// writes, branches and checks still run element by element (1 turns lanes off).
inline constexpr int kLanes = 4;
// Under --float32 a map kernel computes 8 elements at once: its binary32 operations then fill
// an AVX2 register (8 binary32 lanes) where 4 elements used half of one; its binary64 ones
// (det, inv, log: docs/arithmetic.md) take two registers per operation, as two groups of 4.
inline constexpr int kLanes32 = 8;
// Products by zeros known while tracing fold away (jit/zero_fold.h).
inline constexpr bool kFoldZeros = true;

}  // namespace simit::jit
