// SPDX-License-Identifier: MIT
// Probe for experiments/NOTES.md: what a three-input float min costs on sm_90. Aila, Laine &
// Karras's Kepler kernels used the video instruction vmin.s32.s32.s32.min on float bits (valid
// for the non-negative distances it compared); PTX's three-input min.f32 needs sm_100.
// Build: nvcc -arch=sm_90 -cubin -o min3.cubin min3_probe.cu && cuobjdump -sass min3.cubin
__device__ __forceinline__ int vmin3(int a, int b, int c) {
    int d;
    asm("vmin.s32.s32.s32.min %0, %1, %2, %3;" : "=r"(d) : "r"(a), "r"(b), "r"(c));
    return d;
}
__global__ void min3_video(const float* a, float* o) {
    o[0] = __int_as_float(vmin3(__float_as_int(a[0]), __float_as_int(a[1]), __float_as_int(a[2])));
}
__global__ void min3_two_fmnmx(const float* a, float* o) { o[0] = fminf(fminf(a[0], a[1]), a[2]); }
