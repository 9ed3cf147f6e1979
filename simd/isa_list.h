/* The instruction sets of the batch kernels, written once.  Each line
 *   SHL_ISA(name, "compiler flags", cpu_supports)
 * names a helper header simd/<name>/helper.h (the vector verbs), the flags only
 * that ISA's kernel objects get, and an expression, evaluated once at run time
 * in src/dispatch.c, that is nonzero when this CPU and OS can run them.  The
 * #if around a line is the target on which it is compiled in.  Later lines are
 * preferred by the default choice (shl_ctx_create).  Consumers define SHL_ISA
 * and include this file (no include guard):
 *   - the Makefile preprocesses it with $(CC) to get the ISAs and their flags,
 *     and compiles every kernel text simd/<kernel>_batch.h once per ISA, with the
 *     helper included first;
 *   - src/dispatch.c declares the kernels and builds the table of each ISA;
 *   - tests/isa_ctx.h loops the SIMD tests over them. */
SHL_ISA(scalar, "", 1)
#if defined(__x86_64__)
SHL_ISA(avx2, "-mavx2 -mfma", shl__cpu_avx2())
/* After avx2, so the default where both run: on the AMD EPYC (Zen 5) machines
 * of this project 512-bit vectors run at twice the 256-bit FMA peak and every
 * kernel is faster at lmax 8 (bench_simd --isa-only, loaded machine, thread CPU
 * time, gcc and clang): polygon 1.7-1.8x, with gradients too; sphere 1.35-1.45x;
 * light set 1.65-1.8x; interpolation 1.15-1.55x; Hermite at lmax 1 (avx2 kernel)
 * 1.0x. */
#if defined(SHL_AVX512_EMULATE)
/* make AVX512_EMULATE=1: the avx512 kernels through SIMDe's AVX-512 emulation
 * (simd/avx512/helper.h), AVX2 + FMA code (src/dispatch.c: shl__cpu_avx512);
 * -Wno-psabi: gcc notes every 64-byte vector passed without AVX-512 (static
 * inline functions only, so no ABI is crossed). */
SHL_ISA(avx512, "-mavx2 -mfma -Wno-psabi", shl__cpu_avx512())
#else
SHL_ISA(avx512, "-mavx512f -mavx512dq -mavx512vl -mavx512bw -mavx2 -mfma", shl__cpu_avx512())
#endif
#endif
#if defined(__aarch64__)
SHL_ISA(neon, "", 1) /* baseline on AArch64 */
#endif
