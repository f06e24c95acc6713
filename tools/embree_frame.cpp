// embree_frame: an Embree 3 renderer of the viewer's frame, the lab box under `direct` at 500×500 by
// default, for comparing raylab's frame time with Embree's (tools/compare_viewer.py runs both).
//
// The frame is the one `raylab render cornell --integrator direct --spp 1` makes, computed the same way:
//   scene   the 30 triangles of src/scene/cornell.rs (`triangles()`), generated here by the same code:
//           the lab's 555-unit box and blocks, each vertex mapped by q = p·(2/555) − 1 and then (−q.x, −q.y, q.z)
//           (y down), in the same order with the same reflectances;
//   camera  Camera::lab (src/camera.rs): position (0, 0, −3), no rotation, focal length = image height,
//           ray direction normalize(x + 0.5 − W/2, y + 0.5 − H/2, H) through pixel centres;
//   shading src/integrators/mod.rs (`direct_light`, `unshadowed_light`) and src/geometry/ray.rs
//           (`SurfacePoint::on_triangle`, `offset_origin`, `ray_to`): hit point from barycentrics, lab normal
//           n = normalize(cross(v2 − v0, v1 − v0)); lit when cos = (L − p)·n / |L − p| > 0, then one shadow ray
//           from p pushed off the surface by its error bound (γ(7)·Σ|bᵢvᵢ| along n, rounded away from p),
//           trimmed at both ends by 1e-4 of the distance (tnear 0, tfar = dist − 2·1e-4·dist);
//           colour = ρ ∘ (D + N), D = P·cos/(4π r²) when unblocked, P = 14, N = 0.5; misses are black.
// All in float32 with raylab's order of operations (compile with -ffp-contract=off: no fused multiply-adds).
//
// Variants: `single` (rtcIntersect1 / rtcOccluded1, pixel by pixel) and `packet4` (2×2 pixel quads:
// rtcIntersect4, then rtcOccluded4 on the lit lanes), each on the requested thread counts. Threads take
// pairs of rows from a shared counter (a persistent pool, so no thread start-up in the frame time).
//
// Build (see tools/compare_viewer.py, which does it):
//   g++ -O3 -march=native -std=c++17 -ffp-contract=off -pthread tools/embree_frame.cpp -o embree_frame -lembree3
// Run:
//   embree_frame [--width 500] [--height 500] [--warmup 10] [--frames 64] [--threads 1,2]
//                [--apis single,packet4] [--quality low|medium|high] [--coherent 0|1] [--config STR] [--out frame.pfm]
// Defaults: MEDIUM build quality (measured fastest to trace here with HIGH; LOW is ~12 % slower), the
// COHERENT intersect-context flag for packets (~11 % faster than INCOHERENT) and INCOHERENT for single rays
// (no difference); --coherent 0|1 forces one; --config passes a device configuration string to rtcNewDevice.
// Prints one line per variant:
//   embree_frame api=single threads=1 quality=medium size=500x500 frames=64 median_ms=... min_ms=... mean_ms=...
//                cpu_ms=... rays=... mrays_per_s=...
// (wall-clock ms per frame: median, min and mean of the timed frames; cpu_ms: median over frames of the CPU time
// all threads spent on the frame, which other processes on the machine disturb less).
// --out writes the frame (linear RGB, lab units) as a little-endian PFM (rows bottom to top, as PFM has them).
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <pmmintrin.h>
#include <xmmintrin.h>

namespace {

struct V3 {
    float x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(V3 a, V3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline V3 operator*(float s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline V3 operator/(V3 a, float s) { return {a.x / s, a.y / s, a.z / s}; }
// glam's order: (x·x + y·y) + z·z.
inline float dot(V3 a, V3 b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }
inline V3 vabs(V3 a) { return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
// glam's normalize: self · (1 / length).
inline V3 normalize(V3 a) {
    float r = 1.0f / std::sqrt(dot(a, a));
    return r * a;
}

// --- The scene: src/scene/cornell.rs, triangles() ------------------------------------------------
constexpr float L = 555.0f;
const V3 GREEN{0.15f, 0.75f, 0.15f}, PURPLE{0.75f, 0.15f, 0.75f}, YELLOW{0.75f, 0.75f, 0.15f},
    CYAN{0.15f, 0.75f, 0.75f}, WHITE{0.75f, 0.75f, 0.75f}, RED{0.75f, 0.15f, 0.15f}, BLUE{0.15f, 0.15f, 0.75f};
const V3 LIGHT_POSITION{0.0f, -0.5f, -0.7f};
constexpr float LIGHT_POWER = 14.0f;
constexpr float AMBIENT = 0.5f;
const V3 CAMERA_POSITION{0.0f, 0.0f, -3.0f};
constexpr float PI_F = 3.14159265358979323846f;
constexpr float SHADOW_EPSILON = 1e-4f;
// gamma(7) of src/geometry/ray.rs, in f32.
constexpr float EPS_HALF = 1.1920928955078125e-7f * 0.5f;
constexpr float GAMMA7 = (7.0f * EPS_HALF) / (1.0f - 7.0f * EPS_HALF);

struct Scene {
    std::vector<float> verts;  // 3 vertices per triangle, xyz
    std::vector<V3> rho, normal;
    size_t n = 0;
    V3 v(size_t tri, int k) const {
        const float* p = &verts[9 * tri + 3 * k];
        return {p[0], p[1], p[2]};
    }
};

V3 normalise(V3 p) {
    const float s = 2.0f / L;
    V3 q{p.x * s - 1.0f, p.y * s - 1.0f, p.z * s - 1.0f};
    return {-q.x, -q.y, q.z};
}

Scene lab_box() {
    Scene s;
    auto push = [&](V3 a, V3 b, V3 c, V3 color) {
        for (V3 p : {normalise(a), normalise(b), normalise(c)}) s.verts.insert(s.verts.end(), {p.x, p.y, p.z});
        s.rho.push_back(color);
    };
    V3 a{L, 0, 0}, b{0, 0, 0}, c{L, 0, L}, d{0, 0, L};
    V3 e{L, L, 0}, f{0, L, 0}, g{L, L, L}, h{0, L, L};
    push(c, b, a, GREEN);
    push(c, d, b, GREEN);
    push(a, e, c, PURPLE);
    push(c, e, g, PURPLE);
    push(f, b, d, YELLOW);
    push(h, f, d, YELLOW);
    push(e, f, g, CYAN);
    push(f, h, g, CYAN);
    push(g, d, c, WHITE);
    push(g, h, d, WHITE);
    struct Block {
        float base[4][2];
        float height;
        V3 color;
    };
    const Block blocks[2] = {
        {{{290, 114}, {130, 65}, {240, 272}, {82, 225}}, 165.0f, RED},
        {{{423, 247}, {265, 296}, {472, 406}, {314, 456}}, 330.0f, BLUE},
    };
    for (const Block& bl : blocks) {
        V3 lo[4], hi[4];
        for (int i = 0; i < 4; i++) {
            lo[i] = {bl.base[i][0], 0.0f, bl.base[i][1]};
            hi[i] = {bl.base[i][0], bl.height, bl.base[i][1]};
        }
        V3 A = lo[0], B = lo[1], C = lo[2], D = lo[3], E = hi[0], F = hi[1], G = hi[2], H = hi[3];
        const V3 faces[10][3] = {{E, B, A}, {E, F, B}, {F, D, B}, {F, H, D}, {H, C, D},
                                 {H, G, C}, {G, E, C}, {E, A, C}, {G, F, E}, {G, H, F}};
        for (auto& t : faces) push(t[0], t[1], t[2], bl.color);
    }
    s.n = s.rho.size();
    for (size_t i = 0; i < s.n; i++) {
        // Triangle::lab_normal: normalize_or_zero(cross(v2 − v0, v1 − v0)).
        V3 cr = cross(s.v(i, 2) - s.v(i, 0), s.v(i, 1) - s.v(i, 0));
        float r = 1.0f / std::sqrt(dot(cr, cr));
        s.normal.push_back(std::isfinite(r) && r > 0 ? r * cr : V3{0, 0, 0});
    }
    return s;
}

// --- Shading: src/integrators/mod.rs and src/geometry/ray.rs --------------------------------------
struct Shadow {
    V3 org, dir;
    float tfar;
    float irradiance;  // P·cos/(4πr²), the same in every channel
};

inline float round_away(float x, float o) {
    if (o > 0) return std::nextafter(x, INFINITY);
    if (o < 0) return std::nextafter(x, -INFINITY);
    return x;
}

// unshadowed_light: false when the hit does not face the light.
inline bool shadow_ray(const Scene& s, unsigned prim, float b1, float b2, Shadow& out) {
    V3 v0 = s.v(prim, 0), v1 = s.v(prim, 1), v2 = s.v(prim, 2), n = s.normal[prim];
    // SurfacePoint::on_triangle
    float b0 = 1.0f - b1 - b2;
    V3 a = b0 * v0, b = b1 * v1, c = b2 * v2;
    V3 p = (a + b) + c;
    V3 err = GAMMA7 * ((vabs(a) + vabs(b)) + vabs(c));
    V3 to_light = LIGHT_POSITION - p;
    float r2 = dot(to_light, to_light);
    float cs = dot(to_light, n) / std::sqrt(r2);
    if (!(cs > 0.0f && r2 > 0.0f)) return false;
    // SurfacePoint::ray_to(light): offset_origin(target − p), then trim both ends.
    float dd = dot(vabs(n), err);
    V3 off = dd * n;
    V3 w = LIGHT_POSITION - p;
    if (dot(w, n) < 0.0f) off = -1.0f * off;
    V3 po = p + off;
    V3 origin{round_away(po.x, off.x), round_away(po.y, off.y), round_away(po.z, off.z)};
    V3 to = LIGHT_POSITION - origin;
    float dist = std::sqrt(dot(to, to));
    V3 dir = to / dist;
    float skip = dist * SHADOW_EPSILON;
    out.org = origin + skip * dir;
    out.dir = dir;
    out.tfar = dist - 2.0f * skip;
    out.irradiance = LIGHT_POWER * (cs / (4.0f * PI_F * r2));
    return true;
}

inline void shade(const Scene& s, unsigned prim, bool lit_unblocked, float irradiance, float* px) {
    V3 rho = s.rho[prim];
    float k = (lit_unblocked ? irradiance : 0.0f) + AMBIENT;
    px[0] = rho.x * k, px[1] = rho.y * k, px[2] = rho.z * k;
}

// --- The frame --------------------------------------------------------------------------------
struct Frame {
    int w, h;
    float focal;
    std::vector<float> rgb;
    V3 camera_dir(int x, int y) const {
        // Camera::ray(x + 0.5, y + 0.5) with an identity rotation.
        V3 d{(float(x) + 0.5f) - 0.5f * float(w), (float(y) + 0.5f) - 0.5f * float(h), focal};
        return normalize(d);
    }
};

// Rows [y0, y1) ray by ray. Returns the rays cast.
uint64_t rows_single(RTCScene scene, const Scene& s, Frame& fr, int y0, int y1, unsigned ctx_flags) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTCIntersectContextFlags(ctx_flags);
    uint64_t rays = 0;
    for (int y = y0; y < y1; y++) {
        for (int x = 0; x < fr.w; x++) {
            float* px = &fr.rgb[3 * (size_t(y) * fr.w + x)];
            V3 d = fr.camera_dir(x, y);
            RTCRayHit rh;
            rh.ray.org_x = CAMERA_POSITION.x, rh.ray.org_y = CAMERA_POSITION.y, rh.ray.org_z = CAMERA_POSITION.z;
            rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
            rh.ray.tnear = 0.0f, rh.ray.tfar = INFINITY;
            rh.ray.mask = 0xFFFFFFFFu, rh.ray.flags = 0, rh.ray.time = 0.0f, rh.ray.id = 0;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene, &ctx, &rh);
            rays++;
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                px[0] = px[1] = px[2] = 0.0f;
                continue;
            }
            unsigned prim = rh.hit.primID;
            Shadow sh;
            bool lit = shadow_ray(s, prim, rh.hit.u, rh.hit.v, sh);
            bool unblocked = false;
            if (lit) {
                RTCRay r;
                r.org_x = sh.org.x, r.org_y = sh.org.y, r.org_z = sh.org.z;
                r.dir_x = sh.dir.x, r.dir_y = sh.dir.y, r.dir_z = sh.dir.z;
                r.tnear = 0.0f, r.tfar = sh.tfar;
                r.mask = 0xFFFFFFFFu, r.flags = 0, r.time = 0.0f, r.id = 0;
                rtcOccluded1(scene, &ctx, &r);
                rays++;
                unblocked = r.tfar >= 0.0f;  // Embree sets tfar to −inf when occluded
            }
            shade(s, prim, unblocked, sh.irradiance, px);
        }
    }
    return rays;
}

// Rows [y0, y1) (y0 even) in 2×2 pixel quads; a last odd row or column goes in partly valid packets.
uint64_t rows_packet4(RTCScene scene, const Scene& s, Frame& fr, int y0, int y1, unsigned ctx_flags) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTCIntersectContextFlags(ctx_flags);
    uint64_t rays = 0;
    alignas(16) int valid[4];
    alignas(16) RTCRayHit4 rh;
    alignas(16) RTCRay4 sr;
    for (int qy = y0; qy < y1; qy += 2) {
        for (int qx = 0; qx < fr.w; qx += 2) {
            int xs[4] = {qx, qx + 1, qx, qx + 1}, ys[4] = {qy, qy, qy + 1, qy + 1};
            for (int l = 0; l < 4; l++) {
                bool in = xs[l] < fr.w && ys[l] < y1;
                valid[l] = in ? -1 : 0;
                V3 d = in ? fr.camera_dir(xs[l], ys[l]) : V3{0, 0, 1};
                rh.ray.org_x[l] = CAMERA_POSITION.x, rh.ray.org_y[l] = CAMERA_POSITION.y;
                rh.ray.org_z[l] = CAMERA_POSITION.z;
                rh.ray.dir_x[l] = d.x, rh.ray.dir_y[l] = d.y, rh.ray.dir_z[l] = d.z;
                rh.ray.tnear[l] = 0.0f, rh.ray.tfar[l] = INFINITY;
                rh.ray.mask[l] = 0xFFFFFFFFu, rh.ray.flags[l] = 0, rh.ray.time[l] = 0.0f, rh.ray.id[l] = 0;
                rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
                rays += in;
            }
            rtcIntersect4(valid, scene, &ctx, &rh);
            Shadow sh[4];
            alignas(16) int svalid[4];
            bool any = false;
            for (int l = 0; l < 4; l++) {
                bool lit = valid[l] && rh.hit.geomID[l] != RTC_INVALID_GEOMETRY_ID &&
                           shadow_ray(s, rh.hit.primID[l], rh.hit.u[l], rh.hit.v[l], sh[l]);
                svalid[l] = lit ? -1 : 0;
                any |= lit;
                if (!lit) continue;
                sr.org_x[l] = sh[l].org.x, sr.org_y[l] = sh[l].org.y, sr.org_z[l] = sh[l].org.z;
                sr.dir_x[l] = sh[l].dir.x, sr.dir_y[l] = sh[l].dir.y, sr.dir_z[l] = sh[l].dir.z;
                sr.tnear[l] = 0.0f, sr.tfar[l] = sh[l].tfar;
                sr.mask[l] = 0xFFFFFFFFu, sr.flags[l] = 0, sr.time[l] = 0.0f, sr.id[l] = 0;
                rays++;
            }
            if (any) rtcOccluded4(svalid, scene, &ctx, &sr);
            for (int l = 0; l < 4; l++) {
                if (!valid[l]) continue;
                float* px = &fr.rgb[3 * (size_t(ys[l]) * fr.w + xs[l])];
                if (rh.hit.geomID[l] == RTC_INVALID_GEOMETRY_ID) {
                    px[0] = px[1] = px[2] = 0.0f;
                    continue;
                }
                bool unblocked = svalid[l] && sr.tfar[l] >= 0.0f;
                shade(s, rh.hit.primID[l], unblocked, sh[l].irradiance, px);
            }
        }
    }
    return rays;
}

// A persistent pool: run(job) runs job(thread index) on every thread (the caller is thread 0).
class Pool {
public:
    explicit Pool(int n) : n_(n) {
        for (int i = 1; i < n; i++) threads_.emplace_back([this, i] { loop(i); });
    }
    ~Pool() {
        {
            std::lock_guard<std::mutex> g(m_);
            quit_ = true;
            gen_++;
        }
        cv_.notify_all();
        for (auto& t : threads_) t.join();
    }
    void run(const std::function<void(int)>& job) {
        {
            std::lock_guard<std::mutex> g(m_);
            job_ = &job;
            pending_ = n_ - 1;
            gen_++;
        }
        cv_.notify_all();
        job(0);
        std::unique_lock<std::mutex> g(m_);
        done_.wait(g, [this] { return pending_ == 0; });
    }

private:
    void loop(int id) {
        ftz();
        uint64_t seen = 0;
        for (;;) {
            const std::function<void(int)>* job;
            {
                std::unique_lock<std::mutex> g(m_);
                cv_.wait(g, [&] { return gen_ != seen; });
                seen = gen_;
                if (quit_) return;
                job = job_;
            }
            (*job)(id);
            std::lock_guard<std::mutex> g(m_);
            if (--pending_ == 0) done_.notify_one();
        }
    }

public:
    static void ftz() {
        // Embree asks for flush-to-zero and denormals-are-zero in every calling thread.
        _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
        _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    }

private:
    int n_;
    std::vector<std::thread> threads_;
    std::mutex m_;
    std::condition_variable cv_, done_;
    uint64_t gen_ = 0;
    int pending_ = 0;
    bool quit_ = false;
    const std::function<void(int)>* job_ = nullptr;
};

double now_s() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double thread_cpu_s() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    size_t k = v.size() / 2;
    return v.size() % 2 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    size_t i = 0;
    while (i <= s.size()) {
        size_t j = s.find(',', i);
        if (j == std::string::npos) j = s.size();
        if (j > i) out.push_back(s.substr(i, j - i));
        i = j + 1;
    }
    return out;
}

void write_pfm(const std::string& path, const Frame& fr) {
    FILE* f = fopen(path.c_str(), "wb");
    if (!f) {
        fprintf(stderr, "error: cannot write %s\n", path.c_str());
        exit(1);
    }
    fprintf(f, "PF\n%d %d\n-1.0\n", fr.w, fr.h);
    for (int y = fr.h - 1; y >= 0; y--) fwrite(&fr.rgb[3 * size_t(y) * fr.w], 4, 3 * size_t(fr.w), f);
    fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
    int w = 500, h = 500, warmup = 10, frames = 64;
    std::string threads_s = "1,2", apis_s = "single,packet4", quality = "medium", out, config;
    int coherent = -1;  // -1: coherent for packets, incoherent for single rays
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                fprintf(stderr, "error: %s needs a value\n", a.c_str());
                exit(2);
            }
            return argv[++i];
        };
        if (a == "--width") w = atoi(next().c_str());
        else if (a == "--height") h = atoi(next().c_str());
        else if (a == "--warmup") warmup = atoi(next().c_str());
        else if (a == "--frames") frames = atoi(next().c_str());
        else if (a == "--threads") threads_s = next();
        else if (a == "--apis") apis_s = next();
        else if (a == "--quality") quality = next();
        else if (a == "--coherent") coherent = atoi(next().c_str());
        else if (a == "--config") config = next();
        else if (a == "--out") out = next();
        else {
            fprintf(stderr,
                    "usage: embree_frame [--width W] [--height H] [--warmup N] [--frames N] [--threads 1,2]\n"
                    "                    [--apis single,packet4] [--quality low|medium|high] [--coherent 0|1]\n"
                    "                    [--config STR] [--out frame.pfm]\n");
            return 2;
        }
    }
    if (w <= 0 || h <= 0 || frames <= 0) {
        fprintf(stderr, "error: bad size or frame count\n");
        return 2;
    }
    Pool::ftz();
    Scene s = lab_box();

    RTCDevice dev = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!dev) {
        fprintf(stderr, "error: rtcNewDevice failed (%d)\n", int(rtcGetDeviceError(nullptr)));
        return 1;
    }
    RTCScene scene = rtcNewScene(dev);
    RTCBuildQuality q = quality == "high" ? RTC_BUILD_QUALITY_HIGH
                        : quality == "medium" ? RTC_BUILD_QUALITY_MEDIUM
                                              : RTC_BUILD_QUALITY_LOW;
    rtcSetSceneBuildQuality(scene, q);
    RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, q);
    float* vb = (float*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                3 * sizeof(float), 3 * s.n);
    memcpy(vb, s.verts.data(), s.verts.size() * sizeof(float));
    unsigned* ib = (unsigned*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                      3 * sizeof(unsigned), s.n);
    for (unsigned i = 0; i < 3 * s.n; i++) ib[i] = i;
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    double b0 = now_s();
    rtcCommitScene(scene);
    double build_ms = 1e3 * (now_s() - b0);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        fprintf(stderr, "error: Embree scene build failed\n");
        return 1;
    }

    Frame fr{w, h, float(h), std::vector<float>(3 * size_t(w) * h, 0.0f)};
    const int chunk = 2;  // rows per work item: whole pixel quads
    const int items = (h + chunk - 1) / chunk;
    printf("embree_frame build quality=%s tris=%zu build_ms=%.3f embree=%s\n", quality.c_str(), s.n, build_ms,
           RTC_VERSION_STRING);
    bool wrote = false;
    for (const std::string& ts : split(threads_s)) {
        int nt = std::max(1, atoi(ts.c_str()));
        Pool pool(nt);
        for (const std::string& api : split(apis_s)) {
            if (api != "single" && api != "packet4") {
                fprintf(stderr, "error: unknown api %s (single, packet4)\n", api.c_str());
                return 2;
            }
            bool packet = api == "packet4";
            const unsigned ctx_flags = (coherent < 0 ? packet : coherent) ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT
                                                                         : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
            std::atomic<int> next{0};
            std::vector<uint64_t> rays(nt);
            std::vector<double> cpu(nt);
            std::function<void(int)> job = [&](int id) {
                double c0 = thread_cpu_s();
                uint64_t r = 0;
                for (;;) {
                    int i = next.fetch_add(1, std::memory_order_relaxed);
                    if (i >= items) break;
                    int y0 = i * chunk, y1 = std::min(h, y0 + chunk);
                    r += packet ? rows_packet4(scene, s, fr, y0, y1, ctx_flags)
                                : rows_single(scene, s, fr, y0, y1, ctx_flags);
                }
                rays[id] = r;
                cpu[id] = thread_cpu_s() - c0;
            };
            std::vector<double> times, cpus;
            uint64_t frame_rays = 0;
            for (int f = 0; f < warmup + frames; f++) {
                next = 0;
                double t0 = now_s();
                pool.run(job);
                double t = now_s() - t0;
                double c = 0;
                for (double x : cpu) c += x;
                if (f >= warmup) times.push_back(t), cpus.push_back(c);
                frame_rays = 0;
                for (uint64_t r : rays) frame_rays += r;
            }
            double med = median(times), mean = 0;
            for (double t : times) mean += t / times.size();
            printf("embree_frame api=%s threads=%d quality=%s size=%dx%d frames=%d median_ms=%.3f min_ms=%.3f "
                   "mean_ms=%.3f cpu_ms=%.3f rays=%llu mrays_per_s=%.2f\n",
                   api.c_str(), nt, quality.c_str(), w, h, frames, 1e3 * med,
                   1e3 * *std::min_element(times.begin(), times.end()), 1e3 * mean, 1e3 * median(cpus),
                   (unsigned long long)frame_rays, frame_rays / med / 1e6);
            fflush(stdout);
            if (!out.empty() && !wrote) {
                write_pfm(out, fr);
                wrote = true;
            }
        }
    }
    rtcReleaseScene(scene);
    rtcReleaseDevice(dev);
    return 0;
}
