// Runs fused.cu's kernel on the CPU, one sample after another, so that its arithmetic is checked
// against the candle objective on every machine, GPU or not (the unit test of fused.rs builds
// this with the system's C++ compiler). Reads the kernel's arguments as fused.rs writes them
// (six int32, eight f64 constants, then each array as a u64 length and its values) and writes
// the output rows as raw f64.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

struct Index {
    unsigned x = 0, y = 0, z = 0;
};
static Index blockIdx, threadIdx, blockDim;
#define __global__
#define __device__
static double __longlong_as_double(long long bits) {
    double x;
    std::memcpy(&x, &bits, sizeof x);
    return x;
}

#include "fused.cu"

template <typename T> static bool read(FILE* f, std::vector<T>& out) {
    std::uint64_t length = 0;
    if (fread(&length, sizeof length, 1, f) != 1) {
        return false;
    }
    out.resize(length ? length : 1);
    return length == 0 || fread(out.data(), sizeof(T), length, f) == length;
}

int main(int argc, char** argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: fused_host INPUTS OUTPUT\n");
        return 2;
    }
    FILE* in = fopen(argv[1], "rb");
    if (!in) {
        perror(argv[1]);
        return 1;
    }
    std::int32_t s[6];
    Constants k;
    std::vector<double> q, d, a, design_static, goal_static, candidate_real, witness;
    std::vector<std::int32_t> sample_design, sample_goal, capsule_link, capsule_kind, candidate_int;
    bool ok = fread(s, sizeof s, 1, in) == 1 && fread(&k, sizeof k, 1, in) == 1 && read(in, q) && read(in, d) &&
              read(in, a) && read(in, sample_design) && read(in, sample_goal) && read(in, design_static) &&
              read(in, goal_static) && read(in, capsule_link) && read(in, capsule_kind) && read(in, candidate_int) &&
              read(in, candidate_real) && read(in, witness);
    fclose(in);
    if (!ok) {
        fprintf(stderr, "%s: truncated\n", argv[1]);
        return 1;
    }
    std::vector<double> out((std::size_t)s[0] * (2 + 3 * s[1]));
    blockDim.x = 1;
    for (int b = 0; b < s[0]; ++b) {
        blockIdx.x = b;
        paper_objective(s[0], s[1], s[2], s[3], s[4], s[5], k, q.data(), d.data(), a.data(), sample_design.data(),
                        sample_goal.data(), design_static.data(), goal_static.data(), capsule_link.data(),
                        capsule_kind.data(), candidate_int.data(), candidate_real.data(), witness.data(), out.data());
    }
    FILE* o = fopen(argv[2], "wb");
    if (!o || fwrite(out.data(), sizeof(double), out.size(), o) != out.size() || fclose(o) != 0) {
        perror(argv[2]);
        return 1;
    }
    return 0;
}
