// `piezobench instruments`: the instrument families the driver registry
// knows (drivers/registry.hpp), their roles, how each is chosen (from the
// instrument's *IDN? at any SCPI address, or from an address of its own)
// and how to run it against its simulated twin.
#include <iostream>

#include "drivers/registry.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

void register_instruments_command(CLI::App& app, Context& ctx) {
  auto* cmd = app.add_subcommand("instruments", "List the instrument families the drivers support");
  add_json_flag(cmd, ctx);
  cmd->callback([&ctx] {
    ctx.exit_code = run_command(ctx, [&] {
      const auto families = drivers::list_families(drivers::builtin_drivers());
      if (ctx.json) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& f : families) {
          nlohmann::json j = {{"key", f.key},
                              {"description", f.description},
                              {"roles", f.roles},
                              {"chosen_by", f.chosen_by},
                              {"simulated_twin", f.simulated_twin}};
          if (!f.address_form.empty()) j["address_form"] = f.address_form;
          list.push_back(j);
        }
        print_json({{"families", list}});
        return;
      }
      for (const auto& f : families) {
        std::string roles;
        for (const auto& r : f.roles) roles += (roles.empty() ? "" : "+") + r;
        std::cout << f.key << " [" << roles << "] " << f.description << "\n    chosen by "
                  << (f.chosen_by == "address" ? "its address: " + f.address_form
                                               : f.chosen_by + " at any SCPI address")
                  << "\n";
        if (!f.simulated_twin.empty())
          std::cout << "    simulated twin: " << f.simulated_twin << "\n";
      }
    });
  });
}

}  // namespace piezo::cli
