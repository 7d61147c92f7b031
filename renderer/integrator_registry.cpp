#include "renderer/integrator_registry.h"

#include "renderer/error.h"

#include <algorithm>

namespace glaze {
namespace {

struct Registered {
  std::string_view name;
  std::unique_ptr<Integrator> (*make)(const Scene&, const RayTracer&, const Environment&, const IntegratorOptions&);
};

const Registered kIntegrators[] = {
    {PathIntegrator::kName,
     [](const Scene& scene, const RayTracer& tracer, const Environment& environment,
        const IntegratorOptions& options) -> std::unique_ptr<Integrator> {
       return std::make_unique<PathIntegrator>(scene, tracer, environment, options.path, options.path_render);
     }},
    {ShIntegrator::kName,
     [](const Scene& scene, const RayTracer& tracer, const Environment& environment,
        const IntegratorOptions& options) -> std::unique_ptr<Integrator> {
       return std::make_unique<ShIntegrator>(scene, tracer, environment, options.sh);
     }},
};

const Registered& find(std::string_view name) {
  const auto found = std::find_if(std::begin(kIntegrators), std::end(kIntegrators),
                                  [&](const Registered& r) { return r.name == name; });
  if (found != std::end(kIntegrators)) return *found;
  std::string known;
  for (const std::string& n : integrator_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown integrator '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace

const std::vector<std::string>& integrator_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> list;
    for (const Registered& r : kIntegrators) list.emplace_back(r.name);
    return list;
  }();
  return names;
}

void require_integrator(std::string_view name) { find(name); }

std::unique_ptr<Integrator> make_integrator(std::string_view name, const Scene& scene, const RayTracer& tracer,
                                            const Environment& environment, const IntegratorOptions& options) {
  return find(name).make(scene, tracer, environment, options);
}

}  // namespace glaze
