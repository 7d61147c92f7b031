// environment_format.h: environment files as other tools publish them. Besides glaze's
// lat-long maps (latlong.h), a square image of the sphere of directions: Debevec's angular
// map (his light-probe format) or a single mirror-ball image. Both are read by resampling
// them into a lat-long map once, at load time, so that everything downstream (lookups,
// sampling, SH projection) keeps its one lat-long implementation (docs/design.md §3).
//
// Both square formats show the directions seen from a camera looking along -Z with +Y up
// and +X to the right (the map's own frame, the same as a lat-long map's). With disc
// coordinates p = (x, y) in the unit disc (x right, y up; the image's inscribed circle),
// r = |p|, and theta the angle of a direction d from +Z:
//   angular map:  theta = pi r            (Debevec, "Light Probe Image Gallery": (u, v) = (Dx, Dy) r' with
//                                          r' = acos(Dz) / (pi sqrt(Dx^2 + Dy^2)))
//   mirror ball:  theta = 2 asin(r)       (an orthographic view of a mirror ball: the normal is
//                                          (x, y, sqrt(1 - r^2)), the view ray (0, 0, -1) reflects off it)
// and d = (sin(theta) x / r, sin(theta) y / r, cos(theta)). So the image centre is +Z, the
// direction back towards the camera, and the rim is -Z, the direction behind the ball.
#pragma once

#include "renderer/image.h"
#include "renderer/math.h"

#include <string>

namespace glaze {

enum class EnvironmentFormat { automatic, latlong, angular, mirror_ball };

// "latlong", "angular", "mirror_ball" (and "auto" for automatic); throws glaze::Error
// naming `where` and the choices for anything else.
EnvironmentFormat parse_environment_format(const std::string& name, const std::string& where);
const char* environment_format_name(EnvironmentFormat format);

// The direction (unit, the map's frame) at disc coordinates p (|p| <= 1) of a square format.
Vec3d probe_direction(EnvironmentFormat format, const Vec2d& p);
// The disc coordinates of direction d (need not be unit) in a square format.
Vec2d probe_position(EnvironmentFormat format, const Vec3d& d);

// The format of an image read as an environment when none is given: a 2:1 image is
// lat-long; a square one whose pixels outside the inscribed circle are all black is an
// angular map, with a warning saying so (Debevec's published probes are angular maps); a
// square image with light outside its circle throws glaze::Error asking for the format.
// Other shapes are lat-long (Environment warns that they stretch).
EnvironmentFormat recognise_environment_format(const Image& image, const std::string& source);

// A square image in `format` resampled into a lat-long map of 2N x N texels for an N x N
// image: each texel is the solid-angle weighted mean of 2 x 2 bilinear lookups spread over
// it. Directions whose disc radius lies within 1.5 pixels of the rim read the value 1.5
// pixels inside it along their azimuth: the rim's own pixels blend in the black outside
// (and, for a mirror ball, the blind spot behind it). Throws glaze::Error if not square.
Image probe_to_latlong(const Image& probe, EnvironmentFormat format, const std::string& source);

// The inverse, to publish probes: an N x N image in `format` of a lat-long map, each pixel
// the mean of 4 x 4 bilinear lookups over its part inside the circle; black outside it.
Image latlong_to_probe(const Image& latlong, EnvironmentFormat format, int size);

// An environment file read as a lat-long map: in `format`, or recognised when automatic.
Image read_environment_map(const std::string& path, EnvironmentFormat format);

}  // namespace glaze
