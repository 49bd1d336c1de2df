// Synthetic BTF (B): a Lambertian V-groove meso-structure with self-shadowing and masking,
// whose period average has a closed form (the 2D V-cavity of Torrance and Sparrow).
//
// Geometry. Local frame of the macro surface: z = normal, x = across the grooves, y = along
// them. l (toward the light) and v (toward the viewer) are distant directions with z > 0.
// The grooves run along y with period 1 in x. In [0, 1) the profile falls from height 0 at
// x = 0 to depth -d at x = 1/2 and rises back to 0 at x = 1, with facet slope angle g =
// slope_angle (0 < g < pi/2) and d = tan(g)/2. Left facet (x in [0, 1/2)): normal
// n1 = (sin g, 0, cos g); right facet: n2 = (-sin g, 0, cos g). Each facet has length
// L = 1/(2 cos g) per period. Facets are Lambertian with albedo rho; direct light only.
//
// Value. B(x), at the macro position x where the view ray (travelling along -v) crosses
// z = 0, is found by following that ray to the first facet point it hits (masking) and is
//   B = rho * max(0, n_f.l) / l.z   if the ray from that point toward l leaves the groove,
//   B = 0                           otherwise (self-shadowing).
// B is the reflectance factor, pi times the apparent BRDF: light E0 from l gives the macro
// plane the irradiance E0 l.z and the facet the radiance rho/pi E0 n_f.l. Visibility only
// depends on the projections of l and v onto the xz-plane; n_f.l uses the full vector.
// A texel i of W per period is the exact mean of B over [i/W, (i+1)/W): B is piecewise
// constant, so the mean is a finite sum of segment lengths times values.
//
// Closed form of the period average (vgroove_period_average), derived independently of the
// ray casting that vgroove_average does:
//  * Visible fraction a_w,f of facet f from w (w = v or l). Let phi be the projected angle
//    of w from z in the xz-plane (tan phi = w.x / w.z). Take the left facet and phi > 0 (w
//    leans toward the side the facet faces): the point at x0 in [0, 1/2] (height
//    -x0 tan g) sees w iff its ray passes above the opposite rim at x = 1, i.e.
//    -x0 tan g + (1 - x0) cot phi >= 0, i.e. x0 <= cot phi / (tan g + cot phi). The
//    visible part is a top strip of fraction 2 cot phi / (tan g + cot phi)
//    = 2 cos g cos phi / cos(phi - g) = 2 (n_f.z)(w.z) / (n_f.w), which is >= 1 exactly
//    while the opposite facet faces w (phi + g <= pi/2). When w leans the other way the
//    opposite facet lies behind the ray and cannot hide the facet; the ratio above is then
//    >= 1 on its own. The right facet is the mirror image. Hence, for every case,
//      a_w,f = 0                                       if n_f.w <= 0 (back-facing),
//      a_w,f = min(1, 2 (n_f.z)(w.z) / (n_f.w))        otherwise,
//    and the ratio is scale-free, so the full 3D vectors give the projected angles' value.
//  * Lit-and-visible part. The visible part (from v) and the lit part (from l) of a facet
//    are both strips starting at its top edge, so their intersection is the top fraction
//    min(a_v,f, a_l,f).
//  * Macro width. A facet strip of length s, projected along v onto z = 0, covers the
//    macro width s (n_f.v) / v.z. The visible strips tile the period without overlap, so
//      sum_f a_v,f L max(0, n_f.v) / v.z = 1        (masking normalisation).
//    (Both facets fully visible: L (cos(phi-g) + cos(phi+g)) / cos phi = 1; only facet f
//    visible: a_v,f L cos(phi-g) / cos phi = 1.)
//  * Therefore
//      B_avg = (rho / l.z) sum_f max(0, n_f.l) min(a_v,f, a_l,f) L max(0, n_f.v) / v.z
//            = rho / (l.z v.z) sum_f L max(0, n_f.l) max(0, n_f.v) min(a_v,f, a_l,f).
//    The second form is symmetric in l and v: the period-averaged B (pi times the apparent
//    BRDF) is reciprocal, whereas B_avg l.z is not (swapping l and v scales it by
//    l.z / v.z), and neither is B(x) itself (x is where the *view* ray crosses the plane).
//  * Normal incidence, l = v = z: everything is visible and lit, B = rho cos g everywhere.
//
// Preconditions: 0 < slope_angle < pi/2 and v.z > 0 (std::invalid_argument otherwise);
// l.z <= 0 means no direct light: B = 0.
#pragma once

#include <vector>

#include "femto/math.h"

namespace femto::btf {

struct VGroove {
    double slope_angle;  ///< Facet slope angle g in radians, in (0, pi/2).
    double albedo;       ///< Lambertian albedo rho of both facets, in [0, 1].
};

enum class Facet { Left, Right };  ///< Left: x in [0, 1/2), normal n1; Right: n2.

/// Exact average of B over the macro interval [x0, x1] (periodic, any x; B(x0) if x0 == x1).
double vgroove_average(const VGroove& g, double x0, double x1, const Vec3& l, const Vec3& v);

/// The W texel values of one period (texel i = average over [i/W, (i+1)/W)); W >= 1.
std::vector<double> vgroove_texels(const VGroove& g, int W, const Vec3& l, const Vec3& v);

/// B at one macro position x, by ray casting (at a discontinuity: either side's value).
double vgroove_reflectance_at(const VGroove& g, double x, const Vec3& l, const Vec3& v);

/// Closed form of the period average (derivation above), independent of the ray casting.
double vgroove_period_average(const VGroove& g, const Vec3& l, const Vec3& v);

/// a_w,f: the fraction of facet f (a strip from its top edge) visible from direction w.
double vgroove_visible_fraction(const VGroove& g, Facet f, const Vec3& w);

/// Macro width per period covered by the visible part of facet f seen from w (w.z > 0):
/// a_w,f L max(0, n_f.w) / w.z. The two facets' widths sum to 1.
double vgroove_projected_width(const VGroove& g, Facet f, const Vec3& w);

}  // namespace femto::btf
