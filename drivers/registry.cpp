#include "drivers/registry.hpp"

#include <algorithm>
#include <stdexcept>

#include "drivers/infiniium/driver.hpp"
#include "drivers/keysight33500/driver.hpp"
#include "drivers/redpitaya/driver.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/tektronix_awg/driver.hpp"

namespace piezo::drivers {

namespace {
template <class Entry>
void add_entry(std::vector<Entry>& v, Entry e) {
  if (e.key.empty() || !e.accepts || !e.open)
    throw std::invalid_argument("DriverRegistry: an entry needs a key, accepts() and open()");
  for (const auto& x : v)
    if (x.key == e.key)
      throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  v.push_back(std::move(e));
}

template <class Entry>
void list_keys(const std::vector<Entry>& v, std::string& known) {
  for (const auto& e : v) known += (known.empty() ? "" : ", ") + e.key + " (" + e.description + ")";
}
}  // namespace

void DriverRegistry::add_awg(DriverEntry<Awg> e) {
  for (const auto& d : duals_)
    if (d.key == e.key) throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  add_entry(awgs_, std::move(e));
}
void DriverRegistry::add_daq(DriverEntry<Daq> e) {
  for (const auto& d : duals_)
    if (d.key == e.key) throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  add_entry(daqs_, std::move(e));
}
void DriverRegistry::add_dual(DualRoleEntry e) {
  for (const auto& a : awgs_)
    if (a.key == e.key) throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  for (const auto& a : daqs_)
    if (a.key == e.key) throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  add_entry(duals_, std::move(e));
}

InstrumentRoles DriverRegistry::open_instrument(std::unique_ptr<Transport> t) const {
  if (!t) throw std::invalid_argument("DriverRegistry: null transport");
  const std::string idn = query_idn(*t);
  for (const auto& e : duals_)
    if (e.accepts(idn)) return e.open(std::move(t));
  for (const auto& e : awgs_)
    if (e.accepts(idn)) return InstrumentRoles{e.open(std::move(t)), nullptr};
  for (const auto& e : daqs_)
    if (e.accepts(idn)) return InstrumentRoles{nullptr, e.open(std::move(t))};
  std::string known;
  list_keys(duals_, known);
  list_keys(awgs_, known);
  list_keys(daqs_, known);
  throw InstrumentError(t->address() + ": no driver for '" + idn + "'; known: " + known);
}

std::unique_ptr<Awg> DriverRegistry::open_awg(std::unique_ptr<Transport> t) const {
  if (!t) throw std::invalid_argument("DriverRegistry: null transport");
  const std::string idn = query_idn(*t);
  for (const auto& e : awgs_)
    if (e.accepts(idn)) return e.open(std::move(t));
  for (const auto& e : duals_)
    if (e.accepts(idn)) return e.open(std::move(t)).awg;
  std::string known;
  list_keys(awgs_, known);
  list_keys(duals_, known);
  throw InstrumentError(t->address() + ": no AWG driver for '" + idn + "'; known: " + known);
}

std::unique_ptr<Daq> DriverRegistry::open_daq(std::unique_ptr<Transport> t) const {
  if (!t) throw std::invalid_argument("DriverRegistry: null transport");
  const std::string idn = query_idn(*t);
  for (const auto& e : daqs_)
    if (e.accepts(idn)) return e.open(std::move(t));
  for (const auto& e : duals_)
    if (e.accepts(idn)) return e.open(std::move(t)).daq;
  std::string known;
  list_keys(daqs_, known);
  list_keys(duals_, known);
  throw InstrumentError(t->address() + ": no DAQ driver for '" + idn + "'; known: " + known);
}

std::unique_ptr<Awg> DriverRegistry::open_awg(const std::string& key,
                                              std::unique_ptr<Transport> t) const {
  for (const auto& e : awgs_)
    if (e.key == key) return e.open(std::move(t));
  for (const auto& e : duals_)
    if (e.key == key) return e.open(std::move(t)).awg;
  throw std::invalid_argument("DriverRegistry: no AWG driver '" + key + "'");
}

void register_builtin_drivers(DriverRegistry& r) {
  r.add_awg({"keysight33500", "Keysight 33500B/33600A Trueform generators",
             keysight33500::Driver::supports,
             [](std::unique_ptr<Transport> t) -> std::unique_ptr<Awg> {
               return std::make_unique<keysight33500::Driver>(std::move(t));
             }});
  r.add_awg({"tektronix_awg", "Tektronix AWG5000/AWG7000 generators",
             tektronix_awg::Driver::supports,
             [](std::unique_ptr<Transport> t) -> std::unique_ptr<Awg> {
               return std::make_unique<tektronix_awg::Driver>(std::move(t));
             }});
  r.add_daq({"infiniium", "Keysight Infiniium oscilloscopes", infiniium::Driver::supports,
             [](std::unique_ptr<Transport> t) -> std::unique_ptr<Daq> {
               return std::make_unique<infiniium::Driver>(std::move(t));
             }});
  r.add_dual({"redpitaya", "Red Pitaya STEMlab 125-14 (generator and acquisition, one address)",
              redpitaya::supports, [](std::unique_ptr<Transport> t) {
                auto roles = redpitaya::open(std::move(t));
                return InstrumentRoles{std::move(roles.awg), std::move(roles.daq)};
              }});
}

const DriverRegistry& builtin_drivers() {
  static const DriverRegistry r = [] {
    DriverRegistry x;
    register_builtin_drivers(x);
    return x;
  }();
  return r;
}

std::string query_idn(Transport& t) {
  t.send(std::string("*IDN?\n"));
  std::string line;
  std::uint8_t buf[256];
  for (;;) {
    bool eom = false;
    std::size_t n = 0;
    try {
      n = t.receive(buf, sizeof buf, &eom);
    } catch (const TransportError& e) {
      throw TransportError(e.kind(), std::string(e.what()) + " (waiting for the reply to '*IDN?')");
    }
    auto* nl = std::find(buf, buf + n, static_cast<std::uint8_t>('\n'));
    line.append(reinterpret_cast<char*>(buf), reinterpret_cast<char*>(nl));
    if (nl != buf + n) {
      if (nl + 1 != buf + n)
        throw InstrumentError(t.address() + ": unexpected bytes after the *IDN? reply '" + line +
                              "'");
      break;
    }
    if (eom) break;
    if (line.size() > 4096) throw InstrumentError(t.address() + ": *IDN? reply longer than 4 KiB");
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line.empty()) throw InstrumentError(t.address() + ": empty *IDN? reply");
  return line;
}

}  // namespace piezo::drivers
