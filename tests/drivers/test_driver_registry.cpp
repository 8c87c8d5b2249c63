// The driver registry: register_builtin_drivers() lists the drivers, and the
// driver for an address is chosen from the instrument's *IDN? reply.
#include <gtest/gtest.h>

#include "drivers/infiniium/driver.hpp"
#include "drivers/keysight33500/driver.hpp"
#include "drivers/redpitaya/driver.hpp"
#include "drivers/registry.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/sim/loopback_transport.hpp"
#include "drivers/sim/sim_awg.hpp"
#include "drivers/sim/sim_daq.hpp"
#include "drivers/sim/sim_redpitaya.hpp"
#include "drivers/sim/sim_tektronix_awg.hpp"
#include "drivers/tektronix_awg/driver.hpp"
#include "tests/support/doc_table.hpp"
#include "tests/support/rc_physics.hpp"

using namespace piezo;
using namespace piezo::drivers;

namespace {

std::shared_ptr<sim::SimBench> bench() {
  return std::make_shared<sim::SimBench>(std::make_unique<test::RcPhysics>(3140.0, 2.1e-9),
                                         sim::DaqImperfections{}, 1);
}

class Stranger : public sim::ScpiDevice {
 protected:
  std::string idn() const override { return "ACME,WAVEMAKER 9000,1,0"; }
  bool command(const scpi::Command&, const scpi::ProgramMessage&, sim::Reply&) override {
    return false;
  }
};

std::unique_ptr<Transport> loop(std::shared_ptr<sim::ScpiDevice> d) {
  return std::make_unique<sim::LoopbackTransport>(std::move(d), "loop://x");
}

TEST(DriverRegistry, BuiltinDriversAreListedByKey) {
  const auto& r = builtin_drivers();
  ASSERT_EQ(r.awgs().size(), 2u);
  EXPECT_EQ(r.awgs()[0].key, "keysight33500");
  EXPECT_EQ(r.awgs()[1].key, "tektronix_awg");
  ASSERT_EQ(r.daqs().size(), 1u);
  EXPECT_EQ(r.daqs()[0].key, "infiniium");
  ASSERT_EQ(r.duals().size(), 1u);
  EXPECT_EQ(r.duals()[0].key, "redpitaya");
}

// Issue 20: one address, both roles. open_instrument() asks *IDN? once and
// hands back both roles of a Red Pitaya over the one connection; an AWG-only
// or DAQ-only instrument fills its own role alone (the Keysight + Infiniium
// pairing is unchanged); open_awg()/open_daq() take one role of a dual.
TEST(DriverRegistry, ADualRoleInstrumentOpensAsBothRoles) {
  const auto& r = builtin_drivers();
  auto b = bench();
  auto both = r.open_instrument(loop(std::make_shared<sim::SimRedPitaya>(b)));
  EXPECT_NE(dynamic_cast<redpitaya::Generator*>(both.awg.get()), nullptr);
  EXPECT_NE(dynamic_cast<redpitaya::Digitizer*>(both.daq.get()), nullptr);
  EXPECT_EQ(both.awg->identity(), both.daq->identity());
  auto awg_only = r.open_instrument(loop(std::make_shared<sim::SimAwg>(b)));
  EXPECT_NE(dynamic_cast<keysight33500::Driver*>(awg_only.awg.get()), nullptr);
  EXPECT_EQ(awg_only.daq, nullptr);
  auto daq_only = r.open_instrument(loop(std::make_shared<sim::SimDaq>(b)));
  EXPECT_EQ(daq_only.awg, nullptr);
  EXPECT_NE(dynamic_cast<infiniium::Driver*>(daq_only.daq.get()), nullptr);
  EXPECT_NE(dynamic_cast<redpitaya::Generator*>(
                r.open_awg(loop(std::make_shared<sim::SimRedPitaya>(b))).get()),
            nullptr);
  EXPECT_NE(dynamic_cast<redpitaya::Digitizer*>(
                r.open_daq(loop(std::make_shared<sim::SimRedPitaya>(b))).get()),
            nullptr);
  try {
    r.open_instrument(loop(std::make_shared<Stranger>()));
    FAIL() << "opened an unknown instrument";
  } catch (const InstrumentError& e) {
    EXPECT_NE(std::string(e.what()).find("redpitaya"), std::string::npos) << e.what();
  }
}

TEST(DriverRegistry, TheIdnReplyChoosesTheDriver) {
  const auto& r = builtin_drivers();
  auto b = bench();
  auto tek = r.open_awg(loop(std::make_shared<sim::SimTektronixAwg>(b)));
  EXPECT_NE(dynamic_cast<tektronix_awg::Driver*>(tek.get()), nullptr);
  auto key = r.open_awg(loop(std::make_shared<sim::SimAwg>(b)));
  EXPECT_NE(dynamic_cast<keysight33500::Driver*>(key.get()), nullptr);
  auto daq = r.open_daq(loop(std::make_shared<sim::SimDaq>(b)));
  EXPECT_NE(dynamic_cast<infiniium::Driver*>(daq.get()), nullptr);
  auto by_key = r.open_awg("tektronix_awg", loop(std::make_shared<sim::SimTektronixAwg>(b)));
  EXPECT_NE(dynamic_cast<tektronix_awg::Driver*>(by_key.get()), nullptr);
  EXPECT_THROW(r.open_awg("no_such_driver", loop(std::make_shared<sim::SimAwg>(b))),
               std::invalid_argument);
}

TEST(DriverRegistry, AnUnknownInstrumentIsNamedWithTheKnownDrivers) {
  try {
    builtin_drivers().open_awg(loop(std::make_shared<Stranger>()));
    FAIL() << "opened a driver for an unknown instrument";
  } catch (const InstrumentError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("ACME,WAVEMAKER 9000"), std::string::npos) << m;
    EXPECT_NE(m.find("keysight33500"), std::string::npos) << m;
    EXPECT_NE(m.find("tektronix_awg"), std::string::npos) << m;
  }
  // A DAQ address answering as an AWG: no DAQ driver takes it.
  EXPECT_THROW(builtin_drivers().open_daq(loop(std::make_shared<sim::SimTektronixAwg>(bench()))),
               InstrumentError);
}

TEST(DriverRegistry, KeysMustBeUniqueAndEntriesComplete) {
  DriverRegistry r;
  register_builtin_drivers(r);
  EXPECT_THROW(register_builtin_drivers(r), std::invalid_argument);  // every key again
  EXPECT_THROW(r.add_awg({"", "nameless", [](const std::string&) { return true; }, nullptr}),
               std::invalid_argument);
  // A dual-role key is unique across the roles too.
  EXPECT_THROW(r.add_awg({"redpitaya", "again", [](const std::string&) { return true; },
                          [](std::unique_ptr<Transport>) -> std::unique_ptr<Awg> { return nullptr; }}),
               std::invalid_argument);
}

// Board DAQs (issue 20 items 2 and 4): chosen by their address, not *IDN?;
// listed with the others for `piezobench instruments` and the GUI.
TEST(DriverRegistry, BoardDaqsAreChosenByAddressAndListed) {
  const auto& r = builtin_drivers();
  ASSERT_EQ(r.board_daqs().size(), 1u);
  EXPECT_EQ(r.board_daqs()[0].key, "comedi");
  EXPECT_TRUE(r.board_daqs()[0].accepts("comedi:///dev/comedi0?trigger=pfi0"));
  EXPECT_FALSE(r.board_daqs()[0].accepts(
      "comedi-sim:///dev/comedi0"));  // the embedded bench's, not the registry's
  EXPECT_FALSE(r.board_daqs()[0].accepts("tcp://127.0.0.1:5025"));
  EXPECT_EQ(r.open_board_daq("tcp://127.0.0.1:5025"), nullptr);
  // No /dev/comedi99 anywhere: the real board's open fails naming the device.
  try {
    r.open_board_daq("comedi:///dev/comedi99");
    FAIL() << "opened /dev/comedi99";
  } catch (const InstrumentError& e) {
    EXPECT_NE(std::string(e.what()).find("comedi:///dev/comedi99: cannot open"), std::string::npos)
        << e.what();
  }

  const auto families = list_families(r);
  std::vector<std::string> keys;
  for (const auto& f : families) keys.push_back(f.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"keysight33500", "tektronix_awg", "infiniium",
                                            "redpitaya", "comedi"}));
  for (const auto& f : families) {
    EXPECT_FALSE(f.description.empty()) << f.key;
    EXPECT_FALSE(f.simulated_twin.empty()) << f.key;  // every family has a twin
  }
  EXPECT_EQ(families[3].roles, (std::vector<std::string>{"awg", "daq"}));
  EXPECT_EQ(families[4].chosen_by, "address");
  EXPECT_EQ(families[4].address_form.rfind("comedi:///dev/comediN?", 0), 0u);
  EXPECT_EQ(families[0].chosen_by, "*IDN?");

  DriverRegistry x;
  register_builtin_drivers(x);
  EXPECT_THROW(
      x.add_board_daq({"infiniium", "clash", "", [](const std::string&) { return true; },
                       [](const std::string&) -> std::unique_ptr<Daq> { return nullptr; }}),
      std::invalid_argument);
  EXPECT_THROW(
      x.add_awg({"comedi", "clash", [](const std::string&) { return true; },
                 [](std::unique_ptr<Transport>) -> std::unique_ptr<Awg> { return nullptr; }}),
      std::invalid_argument);
  EXPECT_THROW(x.set_simulated_twin("no_such_driver", "x"), std::invalid_argument);
}

}  // namespace

// drivers/README.md's table of the families is the registry's.
TEST(DriverRegistry, ReadmeTableIsTheRegistrys) {
  const std::string table = family_table_markdown(builtin_drivers());
  EXPECT_EQ(test::doc_table("drivers/README.md", table.substr(0, table.find('\n'))), table)
      << "update drivers/README.md's table of the families to:\n" << table;
}

// What the GUI's "Use" fills in comes from the registry: an in-process twin
// for the *IDN? families that have one, a default address for a board DAQ.
TEST(DriverRegistry, UseAddressesAreData) {
  DriverRegistry x;
  register_builtin_drivers(x);
  EXPECT_THROW(x.set_use_addresses("no_such_driver", "a", "b"), std::invalid_argument);
  for (const auto& f : list_families(x)) {
    if (f.key == "tektronix_awg") {
      EXPECT_EQ(f.awg_address, "sim?awg=tektronix");
    }
    if (f.key == "keysight33500" || f.key == "infiniium") {
      EXPECT_EQ(f.awg_address, "sim");
    }
    if (f.chosen_by == "address") {
      EXPECT_FALSE(f.daq_address.empty()) << f.key;
    }
  }
}
