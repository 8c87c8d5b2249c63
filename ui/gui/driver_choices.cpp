#include "ui/gui/driver_choices.hpp"

#include "drivers/comedi/address.hpp"
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
    if (f.chosen_by == "address") {
      c.how = "chosen by its address: " + f.address_form;
      if (f.key == "comedi") c.daq_address = drivers::comedi::Address{}.to_string();
    } else {
      c.how = "chosen from *IDN? at any tcp:// or usbtmc:// address";
      // The in-process twins: the embedded bench's AWG dialects and its Infiniium.
      if (f.key == "keysight33500" || f.key == "infiniium") c.awg_address = "sim";
      if (f.key == "tektronix_awg") c.awg_address = "sim?awg=tektronix";
    }
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace piezo::gui
