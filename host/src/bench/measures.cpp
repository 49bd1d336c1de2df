#include "bench/measures.h"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace femto::bench {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Bin t of the cube is inside [t0, t1) (a steady image's single "bin" always is).
bool bin_inside(const Cube& c, size_t t, double t0, double t1) {
    if (c.T == 1) return true;
    const double centre = c.start + (double(t) + 0.5) * c.bin_width;
    return centre >= t0 && centre < t1;
}

// Sums of (x - r)^2 less the reference's own variance (when it is known), and of r^2.
struct Sums {
    double se = 0, rr = 0;
    void add(const Cube& x, const Cube& ref, size_t i) {
        const double d = double(x.data[i]) - double(ref.data[i]);
        se += d * d - (ref.variance.empty() ? 0.0 : double(ref.variance[i]));
        rr += double(ref.data[i]) * double(ref.data[i]);
    }
    double rel() const { return rr > 0 ? se / rr : kNaN; }
};

}  // namespace

Cube without_variance(Cube c) {
    c.variance.clear();
    return c;
}

void check_same_shape(const Cube& x, const Cube& ref) {
    if (!ref.variance.empty() && ref.variance.size() != ref.data.size())
        throw std::runtime_error("the reference's variance does not match its cube");
    if (x.H != ref.H || x.W != ref.W || x.T != ref.T || x.C != ref.C)
        throw std::runtime_error("the render and its reference differ in shape ([" +
                                 std::to_string(x.H) + ", " + std::to_string(x.W) + ", " +
                                 std::to_string(x.T) + ", " + std::to_string(x.C) + "] against [" +
                                 std::to_string(ref.H) + ", " + std::to_string(ref.W) + ", " +
                                 std::to_string(ref.T) + ", " + std::to_string(ref.C) + "])");
}

double rel_mse(const Cube& x, const Cube& ref, double t0, double t1) {
    check_same_shape(x, ref);
    Sums s;
    for (size_t p = 0; p < x.H * x.W; ++p)
        for (size_t t = 0; t < x.T; ++t) {
            if (!bin_inside(x, t, t0, t1)) continue;
            const size_t i = (p * x.T + t) * x.C;
            for (size_t c = 0; c < x.C; ++c) s.add(x, ref, i + c);
        }
    return s.rel();
}

double rel_mse(const Cube& x, const Cube& ref) {
    return rel_mse(x, ref, -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity());
}

double pixel_rel_mse(const Cube& x, const Cube& ref, double t0, double t1) {
    check_same_shape(x, ref);
    double sum = 0;
    size_t lit = 0;
    for (size_t p = 0; p < x.H * x.W; ++p) {
        Sums s;
        for (size_t t = 0; t < x.T; ++t) {
            if (!bin_inside(x, t, t0, t1)) continue;
            const size_t i = (p * x.T + t) * x.C;
            for (size_t c = 0; c < x.C; ++c) s.add(x, ref, i + c);
        }
        if (s.rr > 0) sum += s.rel(), ++lit;
    }
    return lit ? sum / double(lit) : kNaN;
}

namespace {
size_t pixel_index(const Cube& x, int px, int py) {
    if (px < 0 || py < 0 || size_t(px) >= x.W || size_t(py) >= x.H)
        throw std::runtime_error("pixel (" + std::to_string(px) + ", " + std::to_string(py) +
                                 ") is outside the " + std::to_string(x.W) + " x " +
                                 std::to_string(x.H) + " film");
    return size_t(py) * x.W + size_t(px);
}
}  // namespace

double pixel_profile_rel_mse(const Cube& x, const Cube& ref, int px, int py) {
    check_same_shape(x, ref);
    const size_t p = pixel_index(x, px, py);
    Sums s;
    for (size_t i = p * x.T * x.C; i < (p + 1) * x.T * x.C; ++i) s.add(x, ref, i);
    return s.rel();
}

std::vector<double> pixel_profile(const Cube& x, int px, int py) {
    const size_t p = pixel_index(x, px, py);
    std::vector<double> out(x.T, 0.0);
    for (size_t t = 0; t < x.T; ++t)
        for (size_t c = 0; c < x.C; ++c) out[t] += x.data[(p * x.T + t) * x.C + c] / double(x.C);
    return out;
}

std::vector<double> frame_rel_mse(const Cube& x, const Cube& ref) {
    check_same_shape(x, ref);
    std::vector<Sums> frames(x.T);
    for (size_t p = 0; p < x.H * x.W; ++p)
        for (size_t t = 0; t < x.T; ++t) {
            const size_t i = (p * x.T + t) * x.C;
            for (size_t c = 0; c < x.C; ++c) frames[t].add(x, ref, i + c);
        }
    std::vector<double> out;
    for (const Sums& s : frames) out.push_back(s.rel());
    return out;
}

double resolved_frame_rel_mse(const Cube& x, const Cube& ref) {
    check_same_shape(x, ref);
    std::vector<Sums> frames(x.T);
    std::vector<double> noise(x.T, 0.0);  // sum of Var r per frame
    for (size_t p = 0; p < x.H * x.W; ++p)
        for (size_t t = 0; t < x.T; ++t) {
            const size_t i = (p * x.T + t) * x.C;
            for (size_t c = 0; c < x.C; ++c) {
                frames[t].add(x, ref, i + c);
                if (!ref.variance.empty()) noise[t] += ref.variance[i + c];
            }
        }
    double sum = 0;
    size_t resolved = 0;
    for (size_t t = 0; t < x.T; ++t)
        if (frames[t].rr > 0 && noise[t] < 0.05 * frames[t].rr) sum += frames[t].rel(), ++resolved;
    return resolved ? sum / double(resolved) : kNaN;
}

double energy_error(const Cube& x, const Cube& ref) {
    check_same_shape(x, ref);
    double sx = 0, sr = 0;
    for (size_t i = 0; i < x.size(); ++i) sx += x.data[i], sr += ref.data[i];
    return sr != 0 ? (sx - sr) / sr : kNaN;
}

double student_t975(int dof) {
    // Exact to 3 digits for 1 ... 30 (the table every statistics text prints); the
    // expansion of t in powers of 1 / dof around the normal quantile beyond.
    static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306,
                                   2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120,
                                   2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
                                   2.060,  2.056, 2.052, 2.048, 2.045, 2.042};
    if (dof < 1) return kNaN;
    if (dof <= 30) return table[dof - 1];
    const double z = 1.959964, n = dof;
    return z + (z * z * z + z) / (4 * n) +
           (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * n * n);
}

double Fit::seconds_at(double error) const {
    return std::exp((std::log(error) - intercept) / slope);
}

Fit fit_log_log(const std::vector<double>& seconds, const std::vector<double>& errors) {
    std::vector<double> lx, ly;
    for (size_t i = 0; i < seconds.size() && i < errors.size(); ++i)
        if (seconds[i] > 0 && errors[i] > 0 && std::isfinite(errors[i]))
            lx.push_back(std::log(seconds[i])), ly.push_back(std::log(errors[i]));
    Fit f;
    f.n = int(lx.size());
    if (f.n < 2) return {kNaN, kNaN, kNaN, f.n};
    double mx = 0, my = 0;
    for (int i = 0; i < f.n; ++i) mx += lx[i], my += ly[i];
    mx /= f.n, my /= f.n;
    double sxx = 0, sxy = 0;
    for (int i = 0; i < f.n; ++i)
        sxx += (lx[i] - mx) * (lx[i] - mx), sxy += (lx[i] - mx) * (ly[i] - my);
    if (!(sxx > 0)) return {kNaN, kNaN, kNaN, f.n};
    f.slope = sxy / sxx;
    f.intercept = my - f.slope * mx;
    if (f.n < 3) {
        f.slope_ci95 = kNaN;
        return f;
    }
    double rss = 0;
    for (int i = 0; i < f.n; ++i) {
        const double r = ly[i] - (f.intercept + f.slope * lx[i]);
        rss += r * r;
    }
    f.slope_ci95 = student_t975(f.n - 2) * std::sqrt(rss / (f.n - 2) / sxx);
    return f;
}

namespace {

double ratio_of(const Fit& a, const Fit& b, const std::vector<double>& errors_a) {
    double log_mean = 0;
    int n = 0;
    for (double e : errors_a)
        if (e > 0 && std::isfinite(e)) log_mean += std::log(e), ++n;
    if (n == 0 || !std::isfinite(a.slope) || !std::isfinite(b.slope) || a.slope >= 0 ||
        b.slope >= 0)
        return kNaN;
    const double target = std::exp(log_mean / n);
    return b.seconds_at(target) / a.seconds_at(target);
}

}  // namespace

Ratio equal_error_ratio(const std::vector<double>& seconds_a, const std::vector<double>& errors_a,
                        const std::vector<double>& seconds_b, const std::vector<double>& errors_b) {
    Ratio r;
    r.value =
        ratio_of(fit_log_log(seconds_a, errors_a), fit_log_log(seconds_b, errors_b), errors_a);
    std::mt19937_64 rng(20141201);  // fixed: the interval reproduces run to run
    std::vector<double> samples;
    auto resample = [&](const std::vector<double>& s, const std::vector<double>& e,
                        std::vector<double>& rs, std::vector<double>& re) {
        std::uniform_int_distribution<size_t> pick(0, s.size() - 1);
        rs.clear(), re.clear();
        for (size_t i = 0; i < s.size(); ++i) {
            const size_t k = pick(rng);
            rs.push_back(s[k]), re.push_back(e[k]);
        }
    };
    if (seconds_a.size() >= 3 && seconds_b.size() >= 3) {
        std::vector<double> sa, ea, sb, eb;
        for (int k = 0; k < 2000; ++k) {
            resample(seconds_a, errors_a, sa, ea);
            resample(seconds_b, errors_b, sb, eb);
            const double v = ratio_of(fit_log_log(sa, ea), fit_log_log(sb, eb), ea);
            if (std::isfinite(v)) samples.push_back(v);
        }
    }
    // The interval describes the resamples whose fits worked; when more than 5 % failed (too
    // few distinct budgets drawn, a slope >= 0), it would describe a lucky subset: none then.
    if (samples.size() < 1900) {
        r.lo = r.hi = kNaN;
        return r;
    }
    std::sort(samples.begin(), samples.end());
    r.lo = samples[size_t(0.025 * double(samples.size()))];
    r.hi = samples[std::min(samples.size() - 1, size_t(0.975 * double(samples.size())))];
    return r;
}

double process_cpu_seconds() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

double median(std::vector<double> v) {
    if (v.empty()) return kNaN;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Ratio paired_median_ratio(const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> ratios;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) ratios.push_back(b[i] / a[i]);
    Ratio r{median(ratios), kNaN, kNaN};
    if (ratios.size() < 3) return r;
    std::mt19937_64 rng(20141201);
    std::uniform_int_distribution<size_t> pick(0, ratios.size() - 1);
    std::vector<double> samples, s(ratios.size());
    for (int k = 0; k < 2000; ++k) {
        for (double& x : s) x = ratios[pick(rng)];
        samples.push_back(median(s));
    }
    std::sort(samples.begin(), samples.end());
    r.lo = samples[size_t(0.025 * double(samples.size()))];
    r.hi = samples[size_t(0.975 * double(samples.size()))];
    return r;
}

}  // namespace femto::bench
