// SPDX-License-Identifier: MIT
// Probe: does scale_exponent's downward correction (accel/layouts/cwbvh_convert.cpp) ever run?
// g++ -O2 cwbvh-scale-exponent-guard.cpp && ./a.out
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
int main() {
    long fired = 0, n = 0;
    std::mt19937_64 rng(1);
    auto probe = [&](double extent) {
        if (!(extent > 0.0) || !std::isfinite(extent)) return;
        int e = int(std::ceil(std::log2(extent / 255.0)));
        while (255.0 * std::ldexp(1.0, e) < extent) ++e;
        ++n;
        if (255.0 * std::ldexp(1.0, e - 1) >= extent) ++fired;
    };
    for (int k = -140; k < 119; ++k) {
        float base = float(255.0 * std::ldexp(1.0, k));
        float x = base;
        for (int j = 0; j < 2000; ++j) {
            probe(x);
            x = std::nextafter(x, 0.0f);
        }
        x = base;
        for (int j = 0; j < 2000; ++j) {
            probe(x);
            x = std::nextafter(x, INFINITY);
        }
        float p = std::ldexp(1.0f, k);
        for (int j = 0; j < 200; ++j) {
            probe(p);
            p = std::nextafter(p, 0.0f);
        }
    }
    std::uniform_int_distribution<unsigned> u(1, 0x7f7fffffu);
    for (int i = 0; i < 20000000; ++i) {
        unsigned b = u(rng);
        float f;
        std::memcpy(&f, &b, 4);
        probe(f);
    }
    std::printf("%ld of %ld probes needed the downward correction\n", fired, n);
}
