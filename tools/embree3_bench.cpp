// Embree 3 anchor harness: build time and ray-casting throughput on the canonical workloads.
// A copy of ../shared/bench/embree3_bench.cpp (the shared harness, which we do not edit), extended with the
// surface workloads of tools/gen_surface_rays.py (issue 11):
//   bounce          rays/MESH.bounce.rays, closest hit, tnear 0, tfar inf, context flag INCOHERENT,
//                   reference ref/MESH.bounce.ref.bin (f32 t, u32 prim per ray)
//   surface_shadow  rays/MESH.surface_shadow.rays, any hit, tnear 0, tfar = tfar_surface_shadow of
//                   rays/MESH.surface.json (or --surface-tfar T), INCOHERENT, ref/MESH.surface_shadow.occ.bin
// They run when their ray files exist (and are selected), with the same APIs as the others.
// --workloads primary,incoherent,shadow,bounce,surface_shadow selects workloads (default: all).
// --write-ref writes the reference hits of the selected workloads from the rtc1 runs (rtc1 if listed,
// else the first API) of the first thread count, with quality high if listed, else the first quality.
// Build: g++ -O3 -march=native -std=c++17 -pthread tools/embree3_bench.cpp -I../shared/bench \
//          -o DATA/bin/embree3_bench_ext -lembree3      (tools/compare_embree.py does it when needed)
// usage: embree3_bench ANCHOR_DIR MESH [--runs N] [--build-threads N] [--build-only] [--write-ref]
//                      [--quality high,medium] [--apis 1,8,1M] [--threads 1,2]
//                      [--workloads primary,incoherent,shadow,bounce,surface_shadow] [--surface-tfar T]
// Prints CSV lines: impl,mesh,workload,variant,threads,mrays_per_s,median_ms,build_ms,check
#include <embree3/rtcore.h>

#include <sstream>

#include "common.h"

static std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(item);
    return out;
}

static bool file_exists(const std::string& path) {
    FILE* f = fopen(path.c_str(), "rb");
    if (f) fclose(f);
    return f != nullptr;
}

// The number after "key": in a small JSON file (no JSON library needed for one flat field).
static bool json_number(const std::string& path, const std::string& key, double* out) {
    FILE* f = fopen(path.c_str(), "rb");
    if (!f) return false;
    std::string text;
    char buf[4096];
    size_t got;
    while ((got = fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, got);
    fclose(f);
    size_t at = text.find("\"" + key + "\"");
    if (at == std::string::npos) return false;
    at = text.find(':', at);
    if (at == std::string::npos) return false;
    char* end = nullptr;
    double v = strtod(text.c_str() + at + 1, &end);
    if (end == text.c_str() + at + 1) return false;
    *out = v;
    return true;
}

// One workload: its rays, tfar, query and context flag.
struct Work {
    std::string name;
    const Rays* rays;
    float tfar;
    bool any;  // occluded (any hit) instead of closest hit
    RTCIntersectContextFlags cflags;
};

static RTCScene build_scene(RTCDevice dev, const Mesh& m, RTCBuildQuality q, double* commit_s) {
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneBuildQuality(scene, q);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, q);
    float* vb = (float*)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                3 * sizeof(float), m.nv);
    memcpy(vb, m.v.data(), m.v.size() * 4);
    unsigned* ib = (unsigned*)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                      3 * sizeof(unsigned), m.nt);
    memcpy(ib, m.idx.data(), m.idx.size() * 4);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    double t0 = now_s();
    rtcCommitScene(scene);
    *commit_s = now_s() - t0;
    return scene;
}

static inline void fill_ray(RTCRay& r, const float* s, float tfar) {
    r.org_x = s[0], r.org_y = s[1], r.org_z = s[2], r.tnear = 0.f;
    r.dir_x = s[3], r.dir_y = s[4], r.dir_z = s[5], r.time = 0.f;
    r.tfar = tfar, r.mask = 0xFFFFFFFFu, r.id = 0, r.flags = 0;
}

int main(int argc, char** argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s ANCHOR_DIR MESH [options]\n", argv[0]);
        return 2;
    }
    std::string dir = argv[1], name = argv[2];
    int runs = 7, build_threads = 2;
    bool build_only = false, write_ref = false;
    std::vector<std::string> qualities = {"high", "medium"}, apis = {"1", "8", "1M"};
    std::vector<int> thread_counts = {1, 2};
    std::vector<std::string> selected = {"primary", "incoherent", "shadow", "bounce", "surface_shadow"};
    double surface_tfar = NAN;
    for (int i = 3; i < argc; i++) {
        std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) die("missing value for", a);
            return argv[++i];
        };
        if (a == "--runs") runs = atoi(next().c_str());
        else if (a == "--build-threads") build_threads = atoi(next().c_str());
        else if (a == "--build-only") build_only = true;
        else if (a == "--write-ref") write_ref = true;
        else if (a == "--quality") qualities = split(next());
        else if (a == "--apis") apis = split(next());
        else if (a == "--threads") {
            thread_counts.clear();
            for (auto& s : split(next())) thread_counts.push_back(atoi(s.c_str()));
        } else if (a == "--workloads") selected = split(next());
        else if (a == "--surface-tfar") surface_tfar = atof(next().c_str());
        else die("unknown option", a);
    }
    Mesh mesh = load_mesh(dir + "/mesh/" + name + ".tri");
    std::string cfg = "threads=" + std::to_string(build_threads) + ",set_affinity=0";
    if (getenv("EMBREE_VERBOSE")) cfg += ",verbose=1";
    RTCDevice dev = rtcNewDevice(cfg.c_str());
    if (!dev) die("rtcNewDevice failed", cfg);

    // shadow tfar = float32(|bbox diagonal|), identical to gen_workloads.py
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < mesh.nv; i++)
        for (int k = 0; k < 3; k++) lo[k] = std::min(lo[k], mesh.v[3 * i + k]), hi[k] = std::max(hi[k], mesh.v[3 * i + k]);
    double dx = double(hi[0]) - lo[0], dy = double(hi[1]) - lo[1], dz = double(hi[2]) - lo[2];
    float tfar_shadow = float(std::sqrt(dx * dx + dy * dy + dz * dz));

    auto want = [&](const char* w) { return std::find(selected.begin(), selected.end(), w) != selected.end(); };
    for (auto& w : selected)
        if (w != "primary" && w != "incoherent" && w != "shadow" && w != "bounce" && w != "surface_shadow")
            die("unknown workload", w);
    std::string rays_dir = dir + "/rays/" + name;
    if (std::isnan(surface_tfar)) {
        if (!json_number(rays_dir + ".surface.json", "tfar_surface_shadow", &surface_tfar))
            surface_tfar = double(1.0f - 1e-4f);
    }
    Rays prim_rays, inco_rays, bounce_rays, sshadow_rays;
    std::vector<Work> works;
    if (!build_only) {
        const auto I = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
        if (want("primary")) {
            prim_rays = load_rays(rays_dir + ".primary.rays");
            works.push_back({"primary", &prim_rays, INFINITY, false, RTC_INTERSECT_CONTEXT_FLAG_COHERENT});
        }
        if (want("incoherent") || want("shadow")) inco_rays = load_rays(rays_dir + ".incoherent.rays");
        if (want("incoherent")) works.push_back({"incoherent", &inco_rays, INFINITY, false, I});
        if (want("shadow")) works.push_back({"shadow", &inco_rays, tfar_shadow, true, I});
        if (want("bounce")) {
            if (file_exists(rays_dir + ".bounce.rays")) {
                bounce_rays = load_rays(rays_dir + ".bounce.rays");
                works.push_back({"bounce", &bounce_rays, INFINITY, false, I});
            } else fprintf(stderr, "note: no %s.bounce.rays, bounce skipped\n", rays_dir.c_str());
        }
        if (want("surface_shadow")) {
            if (file_exists(rays_dir + ".surface_shadow.rays")) {
                sshadow_rays = load_rays(rays_dir + ".surface_shadow.rays");
                works.push_back({"surface_shadow", &sshadow_rays, float(surface_tfar), true, I});
            } else fprintf(stderr, "note: no %s.surface_shadow.rays, surface_shadow skipped\n", rays_dir.c_str());
        }
    }
    const std::string ref_quality =
        std::find(qualities.begin(), qualities.end(), "high") != qualities.end() ? "high" : qualities[0];
    const std::string ref_api = std::find(apis.begin(), apis.end(), "1") != apis.end() ? "1" : apis[0];
    printf("impl,mesh,workload,variant,threads,mrays_per_s,median_ms,build_ms,check\n");
    for (auto& qs : qualities) {
        RTCBuildQuality q = qs == "high" ? RTC_BUILD_QUALITY_HIGH
                            : qs == "low" ? RTC_BUILD_QUALITY_LOW
                                          : RTC_BUILD_QUALITY_MEDIUM;
        // Build timing: one warm-up build, then median of 5 clean builds (rtcCommitScene only).
        RTCScene scene = nullptr;
        Timed bt = time_runs(5, build_threads == 1 ? 1 : 0, [&]() {
            double s;
            RTCScene sc = build_scene(dev, mesh, q, &s);
            if (scene) rtcReleaseScene(scene);
            scene = sc;
            return s;
        });
        double build_ms = bt.median_s * 1e3;
        printf("embree3,%s,build,%s-bt%d,%d,,,%.2f,kept=%d rej=%d\n", name.c_str(), qs.c_str(), build_threads,
               build_threads, build_ms, bt.kept, bt.rejected);
        fflush(stdout);
        if (build_only) {
            rtcReleaseScene(scene);
            continue;
        }
        for (const Work& wk : works) {
            const char* wname = wk.name.c_str();
            const Rays& R = *wk.rays;
            size_t n = R.n;
            float tfar = wk.tfar;
            const bool any = wk.any;
            std::vector<float> T(n);
            std::vector<uint32_t> P(n);
            std::vector<uint8_t> O(n);
            RTCIntersectContextFlags cflags = wk.cflags;
            for (auto& api : apis) {
                std::function<void(size_t, size_t)> body;
                if (api == "1") {
                    body = [&](size_t b, size_t e) {
                        RTCIntersectContext ctx;
                        rtcInitIntersectContext(&ctx);
                        ctx.flags = cflags;
                        for (size_t i = b; i < e; i++) {
                            const float* s = &R.r[6 * i];
                            if (any) {
                                RTCRay r;
                                fill_ray(r, s, tfar);
                                rtcOccluded1(scene, &ctx, &r);
                                O[i] = r.tfar < 0.f;
                            } else {
                                RTCRayHit rh;
                                fill_ray(rh.ray, s, tfar);
                                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                                rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
                                rtcIntersect1(scene, &ctx, &rh);
                                bool h = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                                T[i] = h ? rh.ray.tfar : INFINITY;
                                P[i] = h ? rh.hit.primID : 0xFFFFFFFFu;
                            }
                        }
                    };
                } else if (api == "8") {
                    body = [&](size_t b, size_t e) {
                        RTCIntersectContext ctx;
                        rtcInitIntersectContext(&ctx);
                        ctx.flags = cflags;
                        alignas(64) RTCRayHit8 rh;
                        alignas(32) int valid[8];
                        for (size_t i0 = b; i0 < e; i0 += 8) {
                            RTCRay8& r = rh.ray;
                            for (int k = 0; k < 8; k++) {
                                size_t i = i0 + k;
                                valid[k] = i < e ? -1 : 0;
                                const float* s = &R.r[6 * std::min(i, e - 1)];
                                r.org_x[k] = s[0], r.org_y[k] = s[1], r.org_z[k] = s[2], r.tnear[k] = 0.f;
                                r.dir_x[k] = s[3], r.dir_y[k] = s[4], r.dir_z[k] = s[5], r.time[k] = 0.f;
                                r.tfar[k] = tfar, r.mask[k] = 0xFFFFFFFFu, r.id[k] = k, r.flags[k] = 0;
                                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                            }
                            if (any) {
                                rtcOccluded8(valid, scene, &ctx, &r);
                                for (int k = 0; k < 8 && i0 + k < e; k++) O[i0 + k] = r.tfar[k] < 0.f;
                            } else {
                                rtcIntersect8(valid, scene, &ctx, &rh);
                                for (int k = 0; k < 8 && i0 + k < e; k++) {
                                    bool h = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                                    T[i0 + k] = h ? r.tfar[k] : INFINITY;
                                    P[i0 + k] = h ? rh.hit.primID[k] : 0xFFFFFFFFu;
                                }
                            }
                        }
                    };
                } else if (api == "1M") {
                    body = [&](size_t b, size_t e) {
                        RTCIntersectContext ctx;
                        rtcInitIntersectContext(&ctx);
                        ctx.flags = cflags;
                        const size_t M = 256;
                        std::vector<RTCRayHit> rh(M);
                        for (size_t i0 = b; i0 < e; i0 += M) {
                            size_t m = std::min(M, e - i0);
                            for (size_t k = 0; k < m; k++) {
                                fill_ray(rh[k].ray, &R.r[6 * (i0 + k)], tfar);
                                rh[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
                            }
                            if (any) {
                                rtcOccluded1M(scene, &ctx, (RTCRay*)rh.data(), unsigned(m), sizeof(RTCRayHit));
                                for (size_t k = 0; k < m; k++) O[i0 + k] = rh[k].ray.tfar < 0.f;
                            } else {
                                rtcIntersect1M(scene, &ctx, rh.data(), unsigned(m), sizeof(RTCRayHit));
                                for (size_t k = 0; k < m; k++) {
                                    bool h = rh[k].hit.geomID != RTC_INVALID_GEOMETRY_ID;
                                    T[i0 + k] = h ? rh[k].ray.tfar : INFINITY;
                                    P[i0 + k] = h ? rh[k].hit.primID : 0xFFFFFFFFu;
                                }
                            }
                        }
                    };
                } else die("unknown api", api);
                for (int th : thread_counts) {
                    Timed tr = time_runs(runs, th, [&]() { return run_parallel(n, th, 1024, body); });
                    double med = tr.median_s;
                    std::string base = dir + "/ref/" + name + "." + wname;
                    if (write_ref && qs == ref_quality && api == ref_api && th == thread_counts[0]) {
                        if (any) write_file(base + ".occ.bin", O.data(), n);
                        else {
                            std::vector<uint32_t> buf(2 * n);
                            for (size_t i = 0; i < n; i++) memcpy(&buf[2 * i], &T[i], 4), buf[2 * i + 1] = P[i];
                            write_file(base + ".ref.bin", buf.data(), buf.size() * 4);
                        }
                    }
                    HitCheck c = any ? check_occluded(base + ".occ.bin", O) : check_closest(base + ".ref.bin", T, P);
                    size_t hits = 0;
                    for (size_t i = 0; i < n; i++) hits += any ? O[i] != 0 : P[i] != 0xFFFFFFFFu;
                    printf("embree3,%s,%s,%s-rtc%s,%d,%.3f,%.2f,%.2f,%s hits=%zu kept=%d rej=%d cpu_mrays=%.3f\n", name.c_str(),
                           wname, qs.c_str(), api.c_str(), th, n / med * 1e-6, med * 1e3, build_ms,
                           check_str(c).c_str(), hits, tr.kept, tr.rejected, tr.cpu_rate * 1e-6);
                    fflush(stdout);
                }
            }
        }
        rtcReleaseScene(scene);
    }
    rtcReleaseDevice(dev);
    return 0;
}
