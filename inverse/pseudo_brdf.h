// pseudo_brdf.h: what RGB rendering leaves out, for the paper's Figure 7.
//
// A camera integrates spectra: a diffuse surface of reflectance Rd(lambda) under light
// L(lambda) records in channel c  sum_lambda s_c(lambda) Rd(lambda) L(lambda). glaze,
// like the paper, renders and fits per RGB channel, as if that were Rd_c * L_c. It is
// not: with light spectra spanned by three basis spectra B_i (chosen so that the
// camera sees B_i as the pure primary i), the diffuse response is a 3x3 matrix,
//
//   I_c = sum_i M_ci E_i,   M_ci = sum_lambda s_c(lambda) Rd(lambda) B_i(lambda),
//
// with E the RGB irradiance. An RGB fit finds a diagonal "pseudo-BRDF" that matches M
// only for the colour of the light it was fitted under; rendered in other light, the
// colour shifts, least when it was fitted under white-ish light (where the diagonal
// that M * (1,1,1) defines is what the row sums say).
//
// The model: 31 wavelengths 400..700 nm; camera sensitivities are Gaussians (610, 540,
// 455 nm; widths 28, 28, 25 nm) normalised to see a flat spectrum as (1, 1, 1); light
// basis spectra are Gaussians (610, 540, 460 nm, width 45 nm) mixed so that the camera
// sees each as a primary (the maps used here stay within their gamut, so no light
// spectrum is negative). A reflectance is physical: smooth and within (0, 1) at every
// wavelength, the sigmoid of a quadratic (Jakob and Hanika 2019) that the camera sees,
// under RGB-white light, as close as it can to the RGB Rd asked for (by Ceres). Very
// saturated colours are out of its reach: the paper's red (0.9765, 0.0186, 0) comes out
// as M * (1,1,1) = (0.893, 0.117, 0.000), which is then its true RGB under white light.
// The mirror coat is wavelength-independent (R0 is a scalar), so it needs no matrix.
#pragma once

#include "renderer/camera.h"
#include "renderer/environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"

namespace glaze {

// M for the physical reflectance that looks most like `Rd` under RGB-white light
// (M * (1,1,1) = Rd where Rd is within reach).
Mat3 spectral_diffuse_matrix(const RGB& Rd);

// render_sh of `scene` (one material; its Rd replaced by the matrix M) as the spectral
// camera records it: the mirror term as usual plus the diffuse term M E. Built from
// render_sh by linearity (the diffuse term is linear in Rd and in the light), two
// renders per light primary, so it is exactly glaze's model where the diffuse sum is
// not clamped (it is positive for the maps used here).
Image render_sh_spectral(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                         const PinholeCamera& camera, const ShIntegratorOptions& options, const Mat3& M);

}  // namespace glaze
