# (name, original, mutant): one-line bugs planted in gpu-binned's kernels
M = [
 ("m1-binmap-scale", "const float k = float(kSahBins) * (1.0f - 1e-6f);\n        scale = {e.x", "const float k = float(kSahBins);\n        scale = {e.x"),
 ("m2-sweep-empty-left", "if (!splittable[a] || lane == 31 || nl[a] == 0 || n_right == 0) continue;", "if (!splittable[a] || lane == 31 || n_right == 0) continue;"),
 ("m3-scatter-side-cb", "        side[is_left ? 0 : 1].extend(cs[r]);", "        side[0].extend(cs[r]);"),
 ("m4-tiny-tie-rule", "if (cy < cx || (cy == cx && tri[y][me] < idx)) break;", "if (cy < cx || (cy == cx && tri[y][me] > idx)) break;"),
 ("m5-tiny-equal-centroids", "                if (centre(mine[i - 1], a) == centre(mine[i], a)) continue;\n", ""),
 ("m6-small-right-place", "if (live && !l) tmp[b + m + nr + __popc(br & lt)] = id;", "if (live && !l) tmp[b + m + nr] = id;"),
 ("m7-lefts-bin", "uint32_t k = lane <= uint32_t(s.bin) ?", "uint32_t k = lane < uint32_t(s.bin) ?"),
 ("m8-chunks-tail", "(tasks[k].e - tasks[k].b + kSahChunk - 1) / kSahChunk : 0;", "(tasks[k].e - tasks[k].b) / kSahChunk : 0;"),
]
