// The C ABI from C++ (issues 24, 32), compiled by g++ and linked with libadmittance_ffi.a by
// run.sh beside this file. It loads a deployment folder (`admittance deploy`), replays the
// inputs the Rust reference program recorded (examples/reference_run.rs: the Rust loop of
// the same folder fed a measured motion with a NaN burst and two absurd samples) through
// adm_step and checks, for 100,000 steps:
//   1. no allocation and no free between the first and the last step: malloc, calloc,
//      realloc, free, posix_memalign, aligned_alloc, memalign and operator new/delete are
//      interposed here and counted (the Rust allocator calls malloc: the allocations of
//      adm_create are counted too, which shows the interposition sees them);
//   2. every AdmOutput equals the Rust loop's byte for byte (memcmp), and every status
//      agrees with its fault field;
//   3. the two absurd samples were flagged (ADM_OUT_IMPLAUSIBLE_INPUT) and counted;
//   4. the error paths: a wrong joint count, null pointers, a missing deployment folder.
// It prints adm_create's wall time (issue 32's bar: under 100 ms on a deployed folder).
// Usage: loop_test DEPLOY_DIR DATA_DIR (DATA_DIR holds inputs.bin and outputs.bin).
// Exit status 0 when every check passes, 1 with a message on stderr otherwise.

#include "admittance.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <new>
#include <string>
#include <vector>

// ---- allocation counting -------------------------------------------------------------

extern "C" {
void *__libc_malloc(size_t);
void *__libc_calloc(size_t, size_t);
void *__libc_realloc(void *, size_t);
void __libc_free(void *);
void *__libc_memalign(size_t, size_t);
}

static std::atomic<bool> g_counting{false};
static std::atomic<long> g_allocs{0};
static std::atomic<long> g_frees{0};

static inline void note_alloc() {
    if (g_counting.load(std::memory_order_relaxed)) g_allocs.fetch_add(1, std::memory_order_relaxed);
}
static inline void note_free() {
    if (g_counting.load(std::memory_order_relaxed)) g_frees.fetch_add(1, std::memory_order_relaxed);
}

extern "C" void *malloc(size_t n) {
    note_alloc();
    return __libc_malloc(n);
}
extern "C" void *calloc(size_t count, size_t size) {
    note_alloc();
    return __libc_calloc(count, size);
}
extern "C" void *realloc(void *p, size_t n) {
    note_alloc();
    return __libc_realloc(p, n);
}
extern "C" void free(void *p) {
    if (p) note_free();
    __libc_free(p);
}
extern "C" int posix_memalign(void **out, size_t align, size_t n) {
    note_alloc();
    void *p = __libc_memalign(align, n);
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}
extern "C" void *aligned_alloc(size_t align, size_t n) {
    note_alloc();
    return __libc_memalign(align, n);
}
extern "C" void *memalign(size_t align, size_t n) {
    note_alloc();
    return __libc_memalign(align, n);
}

// operator new and delete, through the counted malloc and free.
void *operator new(size_t n) {
    if (void *p = malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void *operator new[](size_t n) { return operator new(n); }
void operator delete(void *p) noexcept { free(p); }
void operator delete[](void *p) noexcept { free(p); }
void operator delete(void *p, size_t) noexcept { free(p); }
void operator delete[](void *p, size_t) noexcept { free(p); }

// ---- the test ------------------------------------------------------------------------

static int fail(const std::string &msg) {
    std::fprintf(stderr, "loop_test: FAILED: %s\n", msg.c_str());
    return 1;
}

static bool read_file(const std::string &path, std::vector<char> &out) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return false;
    out.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
    return true;
}

static std::string last_error(const AdmHandle *h) {
    char buf[1024];
    adm_last_error(h, buf, sizeof buf);
    return buf;
}

int main(int argc, char **argv) {
    if (argc != 3) return fail("usage: loop_test DEPLOY_DIR DATA_DIR");
    const std::string dir = argv[2];

    // The interposition works: a malloc and a new of this program are counted.
    g_counting = true;
    {
        void *volatile p = malloc(24);
        free(p);
        int *volatile q = new int(3);
        delete q;
    }
    g_counting = false;
    if (g_allocs.load() != 2 || g_frees.load() != 2)
        return fail("the allocation counters did not see this program's malloc and new");

    if (adm_abi_version() != ADM_ABI_VERSION)
        return fail("adm_abi_version() differs from the header's ADM_ABI_VERSION");

    std::vector<char> in_bytes, ref_bytes;
    if (!read_file(dir + "/inputs.bin", in_bytes) || !read_file(dir + "/outputs.bin", ref_bytes))
        return fail("cannot read " + dir + "/inputs.bin or outputs.bin (run reference_run first)");
    if (in_bytes.size() < 16 || std::memcmp(in_bytes.data(), "ADMIN001", 8) != 0 ||
        ref_bytes.size() < 16 || std::memcmp(ref_bytes.data(), "ADMOUT02", 8) != 0)
        return fail("inputs.bin / outputs.bin: not reference_run's format");
    uint32_t n, steps;
    std::memcpy(&n, in_bytes.data() + 8, 4);
    std::memcpy(&steps, in_bytes.data() + 12, 4);
    const size_t in_record = 16 + 6 * 8 * size_t(n);
    if (in_bytes.size() != 16 + steps * in_record ||
        ref_bytes.size() != 16 + steps * sizeof(AdmOutput))
        return fail("inputs.bin / outputs.bin: sizes do not match their headers");

    // A missing deployment folder: null handle, an error naming it.
    AdmConfig bad{};
    bad.abi_version = ADM_ABI_VERSION;
    bad.n_joints = n;
    bad.deployment_path = "no/such/deployment";
    if (adm_create(&bad) != nullptr) return fail("adm_create accepted a missing deployment folder");
    if (last_error(nullptr).find("no/such/deployment") == std::string::npos)
        return fail("adm_last_error does not name the missing folder: " + last_error(nullptr));

    AdmConfig config{};
    config.abi_version = ADM_ABI_VERSION;
    config.n_joints = n;
    config.deployment_path = argv[1];
    config.flags = ADM_CONFIG_WRENCH;
    std::vector<long long> step_ns(steps);  // allocated before counting

    g_allocs = 0;
    g_frees = 0;
    g_counting = true;
    const auto c0 = std::chrono::steady_clock::now();
    AdmHandle *h = adm_create(&config);
    const auto c1 = std::chrono::steady_clock::now();
    g_counting = false;
    const double create_ms = std::chrono::duration<double, std::milli>(c1 - c0).count();
    const long create_allocs = g_allocs.load();
    if (!h) return fail("adm_create: " + last_error(nullptr));
    if (create_allocs == 0)
        return fail("adm_create allocated nothing the counters saw: the interposition is broken");

    // ---- the real-time loop: nothing allocates from here to the last step ----
    size_t mismatches = 0, first_mismatch = size_t(-1), status_errors = 0, faults = 0;
    size_t implausible_flags = 0;
    AdmOutput out;
    g_allocs = 0;
    g_frees = 0;
    g_counting = true;
    for (uint32_t k = 0; k < steps; ++k) {
        const char *rec = in_bytes.data() + 16 + k * in_record;
        AdmInput in;
        std::memset(&in, 0, sizeof in);
        std::memcpy(&in.time, rec, 8);
        std::memcpy(&in.n_joints, rec + 8, 4);
        std::memcpy(&in.flags, rec + 12, 4);
        double *arrays[6] = {in.q, in.qdot, in.tau, in.q_d, in.qdot_d, in.qddot_d};
        for (int a = 0; a < 6; ++a) std::memcpy(arrays[a], rec + 16 + a * 8 * n, 8 * n);

        const auto t0 = std::chrono::steady_clock::now();
        const int32_t status = adm_step(h, &in, &out);
        const auto t1 = std::chrono::steady_clock::now();
        step_ns[k] = std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count();

        const char *expected = ref_bytes.data() + 16 + k * sizeof(AdmOutput);
        if (std::memcmp(&out, expected, sizeof out) != 0) {
            if (mismatches++ == 0) first_mismatch = k;
        }
        if (status != (out.fault == ADM_FAULT_NONE ? ADM_OK : ADM_FAULT)) ++status_errors;
        faults += out.fault != ADM_FAULT_NONE;
        implausible_flags += (out.flags & ADM_OUT_IMPLAUSIBLE_INPUT) != 0;
    }
    g_counting = false;
    const long loop_allocs = g_allocs.load(), loop_frees = g_frees.load();
    // ---- end of the real-time loop ----

    // Error paths: a wrong joint count holds the last output and says why; null pointers.
    AdmInput wrong;
    std::memset(&wrong, 0, sizeof wrong);
    wrong.n_joints = n + 1;
    AdmOutput held;
    const bool joints_ok = adm_step(h, &wrong, &held) == ADM_ERR_JOINTS &&
                           std::memcmp(&held, &out, sizeof out) == 0 &&
                           last_error(h).find("n_joints") != std::string::npos;
    const bool null_ok = adm_step(nullptr, &wrong, &held) == ADM_ERR_NULL &&
                         adm_step(h, nullptr, &held) == ADM_ERR_NULL &&
                         adm_step(h, &wrong, nullptr) == ADM_ERR_NULL;
    adm_destroy(h);

    std::sort(step_ns.begin(), step_ns.end());
    std::printf(
        "loop_test: %u steps of %u joints; adm_create %.1f ms with %ld allocations, during the "
        "loop %ld (frees %ld); outputs bit-identical to Rust in %zu of %u steps (%zu with a "
        "fault, %zu implausible samples flagged); adm_step wall time from C++: median %lld ns, "
        "99th percentile %lld ns, max %lld ns\n",
        steps, n, create_ms, create_allocs, loop_allocs, loop_frees, steps - mismatches, steps,
        faults, implausible_flags,
        step_ns[steps / 2], step_ns[size_t(steps * 0.99)], step_ns[steps - 1]);

    if (loop_allocs != 0 || loop_frees != 0)
        return fail(std::to_string(loop_allocs) + " allocations and " + std::to_string(loop_frees) +
                    " frees during the loop (expected 0)");
    if (mismatches != 0)
        return fail(std::to_string(mismatches) + " outputs differ from the Rust loop's, first at step " +
                    std::to_string(first_mismatch));
    if (status_errors != 0)
        return fail(std::to_string(status_errors) + " statuses disagree with their fault field");
    if (faults == 0) return fail("the reference sequence produced no controller fault to compare");
    if (steps >= 40000 && (implausible_flags != 2 || out.implausible_samples != 2))
        return fail("expected the 2 absurd samples flagged and counted, got " +
                    std::to_string(implausible_flags) + " flags, count " +
                    std::to_string(out.implausible_samples));
    if (!joints_ok) return fail("a wrong n_joints did not return ADM_ERR_JOINTS with the held output");
    if (!null_ok) return fail("a null pointer did not return ADM_ERR_NULL");
    std::printf("loop_test: 7 passed, 0 failed\n");
    return 0;
}
