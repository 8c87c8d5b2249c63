#include "ui/gui/driver_choices.hpp"

#include "drivers/registry.hpp"

namespace piezo::gui {

std::vector<DriverChoice> driver_choices() {
  std::vector<DriverChoice> out;
  for (const auto& f : drivers::list_families(drivers::builtin_drivers())) {
    DriverChoice c;
    c.key = f.key;
    std::string roles;
    for (const auto& r : f.roles) roles += (roles.empty() ? "" : "+") + r;
    c.label = f.key + " [" + roles + "]: " + f.description;
    c.twin = f.simulated_twin;
    c.how = f.chosen_by == "address" ? "chosen by its address: " + f.address_form
                                     : "chosen from *IDN? at any tcp:// or usbtmc:// address";
    // The registry's addresses to use it (drivers/registry.cpp): an in-process twin, a board's default.
    c.awg_address = f.awg_address;
    c.daq_address = f.daq_address;
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace piezo::gui
