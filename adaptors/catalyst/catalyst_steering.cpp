#include "catalyst_steering.hpp"

#include <vtkNew.h>
#include <vtkSMIntVectorProperty.h>
#include <vtkSMParaViewPipelineController.h>
#include <vtkSMPluginManager.h>
#include <vtkSMPropertyHelper.h>
#include <vtkSMProxy.h>
#include <vtkSMProxyManager.h>
#include <vtkSMSessionProxyManager.h>
#include <vtkSmartPointer.h>

#include <fmt/format.h>

namespace spate::catalyst {

namespace {

vtkSMSessionProxyManager* session_proxy_manager() {
  vtkSMProxyManager* pm = vtkSMProxyManager::IsInitialized() ? vtkSMProxyManager::GetProxyManager() : nullptr;
  return pm ? pm->GetActiveSessionProxyManager() : nullptr;
}

vtkSMProxy* steering_proxy() {
  vtkSMSessionProxyManager* pxm = session_proxy_manager();
  return pxm ? pxm->GetProxy("sources", CatalystSteering::kRegistrationName) : nullptr;
}

// write_checkpoint and stop are switches: only switching them on is a request (switching off
// again just re-arms them; see docs/live.md).
bool is_switch(const std::string& name) { return name == "write_checkpoint" || name == "stop"; }

}  // namespace

void SteeringInitial::take(const SteeringChange& c) {
  const auto& v = c.value;
  if (c.name == "gravity" && v.size() == 3) gravity = {v[0], v[1], v[2]};
  if (c.name == "viscosity" && v.size() == 1) viscosity = v[0];
  if (c.name == "phase_viscosity" && v.size() == 2) phase_viscosity = {v[0], v[1]};
  if (c.name == "artificial_viscosity" && v.size() == 1) artificial_viscosity = v[0];
  if (c.name == "insitu_every" && v.size() == 1) insitu_every = static_cast<int>(v[0]);
  if (c.name == "motion_amplitude" && v.size() == 2) motion_amplitude = {v[0], v[1]};
  if (c.name == "motion_frequency" && v.size() == 2) motion_frequency = {v[0], v[1]};
  if (c.name == "face_temperature" && v.size() == 2) face_temperature = {v[0], v[1]};
  if (c.name == "face_heat_flux" && v.size() == 2) face_heat_flux = {v[0], v[1]};
  if (c.name == "spring_stiffness" && v.size() == 2) spring_stiffness = {v[0], v[1]};
  if (c.name == "spring_damping" && v.size() == 2) spring_damping = {v[0], v[1]};
  if (c.name == "hinge_stiffness" && v.size() == 2) hinge_stiffness = {v[0], v[1]};
  if (c.name == "hinge_damping" && v.size() == 2) hinge_damping = {v[0], v[1]};
}

CatalystSteering::CatalystSteering(const std::filesystem::path& xml, const SteeringInitial& initial) {
  vtkSMSessionProxyManager* pxm = session_proxy_manager();
  if (!pxm) throw InSituLoadError("steering: ParaView's proxy manager is not running (start Catalyst first)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(xml, ec)) throw InSituLoadError(fmt::format("steering: no such proxy definition {}", xml.string()));
  if (!pxm->GetPrototypeProxy("sources", kProxyType) &&
      !vtkSMProxyManager::GetProxyManager()->GetPluginManager()->LoadLocalPlugin(xml.c_str()))
    throw InSituLoadError(fmt::format("steering: ParaView could not load {}", xml.string()));
  vtkSmartPointer<vtkSMProxy> proxy;
  proxy.TakeReference(pxm->NewProxy("sources", kProxyType));
  if (!proxy) throw InSituLoadError(fmt::format("steering: {} defines no proxy sources/{}", xml.string(), kProxyType));
  vtkNew<vtkSMParaViewPipelineController> controller;
  controller->InitializeProxy(proxy);
  vtkSMPropertyHelper(proxy, "gravity").Set(initial.gravity.data(), 3);
  vtkSMPropertyHelper(proxy, "viscosity").Set(initial.viscosity);
  vtkSMPropertyHelper(proxy, "phase_viscosity").Set(initial.phase_viscosity.data(), 2);
  vtkSMPropertyHelper(proxy, "artificial_viscosity").Set(initial.artificial_viscosity);
  vtkSMPropertyHelper(proxy, "motion_amplitude").Set(initial.motion_amplitude.data(), 2);
  vtkSMPropertyHelper(proxy, "motion_frequency").Set(initial.motion_frequency.data(), 2);
  vtkSMPropertyHelper(proxy, "face_temperature").Set(initial.face_temperature.data(), 2);
  vtkSMPropertyHelper(proxy, "face_heat_flux").Set(initial.face_heat_flux.data(), 2);
  vtkSMPropertyHelper(proxy, "spring_stiffness").Set(initial.spring_stiffness.data(), 2);
  vtkSMPropertyHelper(proxy, "spring_damping").Set(initial.spring_damping.data(), 2);
  vtkSMPropertyHelper(proxy, "hinge_stiffness").Set(initial.hinge_stiffness.data(), 2);
  vtkSMPropertyHelper(proxy, "hinge_damping").Set(initial.hinge_damping.data(), 2);
  vtkSMPropertyHelper(proxy, "insitu_every").Set(initial.insitu_every);
  vtkSMPropertyHelper(proxy, "write_checkpoint").Set(0);
  vtkSMPropertyHelper(proxy, "stop").Set(0);
  proxy->UpdateVTKObjects();
  controller->RegisterPipelineProxy(proxy, kRegistrationName);
  last_ = values();
}

CatalystSteering::~CatalystSteering() {
  // The proxy belongs to the proxy manager, which the CatalystSink finalises; unregister it while
  // the manager is still up so that nothing refers to it afterwards.
  if (vtkSMSessionProxyManager* pxm = session_proxy_manager())
    if (pxm->GetProxy("sources", kRegistrationName)) pxm->UnRegisterProxy("sources", kRegistrationName, pxm->GetProxy("sources", kRegistrationName));
}

std::map<std::string, std::vector<double>> CatalystSteering::values() const {
  std::map<std::string, std::vector<double>> v;
  vtkSMProxy* proxy = steering_proxy();
  if (!proxy) return v;
  for (auto& p : steering_parameters())
    if (proxy->GetProperty(p.name.c_str())) v[p.name] = vtkSMPropertyHelper(proxy, p.name.c_str()).GetDoubleArray();
  return v;
}

void CatalystSteering::set_for_test(const std::string& name, const std::vector<double>& value) {
  vtkSMProxy* proxy = steering_proxy();
  if (!proxy) return;
  vtkSMPropertyHelper helper(proxy, name.c_str());
  if (vtkSMIntVectorProperty::SafeDownCast(proxy->GetProperty(name.c_str()))) {
    std::vector<int> ints(value.begin(), value.end());
    helper.Set(ints.data(), static_cast<unsigned int>(ints.size()));
  } else {
    helper.Set(value.data(), static_cast<unsigned int>(value.size()));
  }
  proxy->UpdateVTKObjects();
}

std::vector<SteeringChange> CatalystSteering::poll(std::int64_t step, double time) {
  std::vector<SteeringChange> changes;
  auto now = values();
  for (auto& p : steering_parameters()) {  // the documented order, so logs read the same every run
    auto it = now.find(p.name);
    if (it == now.end() || last_[p.name] == it->second) continue;
    if (!(is_switch(p.name) && !it->second.empty() && it->second[0] == 0.0))
      changes.push_back(SteeringChange{step, time, p.name, it->second});
  }
  last_ = std::move(now);
  return changes;
}

}  // namespace spate::catalyst
