#include "drivers/registry.hpp"

#include <algorithm>
#include <stdexcept>

#include "drivers/comedi/address.hpp"
#include "drivers/comedi/driver.hpp"
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

bool DriverRegistry::has_key(const std::string& key) const {
  auto in = [&](const auto& v) {
    return std::any_of(v.begin(), v.end(), [&](const auto& e) { return e.key == key; });
  };
  return in(awgs_) || in(daqs_) || in(duals_) || in(boards_);
}

void DriverRegistry::add_awg(DriverEntry<Awg> e) {
  for (const auto& d : duals_)
    if (d.key == e.key) throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  for (const auto& d : boards_)
    if (d.key == e.key)
      throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  add_entry(awgs_, std::move(e));
}
void DriverRegistry::add_daq(DriverEntry<Daq> e) {
  for (const auto& d : duals_)
    if (d.key == e.key) throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  for (const auto& d : boards_)
    if (d.key == e.key)
      throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  add_entry(daqs_, std::move(e));
}
void DriverRegistry::add_board_daq(BoardDaqEntry e) {
  if (has_key(e.key))
    throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
  add_entry(boards_, std::move(e));
}

std::unique_ptr<Daq> DriverRegistry::open_board_daq(const std::string& address) const {
  for (const auto& e : boards_)
    if (e.accepts(address)) return e.open(address);
  return nullptr;
}

DriverRegistry::Extra& DriverRegistry::extra(const std::string& key) {
  if (!has_key(key)) throw std::invalid_argument("DriverRegistry: no driver '" + key + "'");
  for (auto& x : extras_)
    if (x.key == key) return x;
  extras_.push_back({key, {}, {}, {}});
  return extras_.back();
}

void DriverRegistry::set_simulated_twin(const std::string& key, std::string how) {
  extra(key).twin = std::move(how);
}

std::string DriverRegistry::simulated_twin(const std::string& key) const {
  for (const auto& x : extras_)
    if (x.key == key) return x.twin;
  return {};
}

void DriverRegistry::set_use_addresses(const std::string& key, std::string awg, std::string daq) {
  auto& x = extra(key);
  x.awg_address = std::move(awg);
  x.daq_address = std::move(daq);
}

std::pair<std::string, std::string> DriverRegistry::use_addresses(const std::string& key) const {
  for (const auto& x : extras_)
    if (x.key == key) return {x.awg_address, x.daq_address};
  return {};
}

void DriverRegistry::add_dual(DualRoleEntry e) {
  for (const auto& a : boards_)
    if (a.key == e.key)
      throw std::invalid_argument("DriverRegistry: duplicate driver key '" + e.key + "'");
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
  r.add_board_daq(
      {"comedi", "DAQ boards through Comedi (analog input streaming; written for the NI PCI-6110E)",
       "comedi:///dev/"
       "comediN?trigger=pfiN|software&edge=rising|falling&aref=diff|rse|nrse&channels=C1,C2",
       [](const std::string& a) { return a.starts_with("comedi://"); },
       [](const std::string& a) -> std::unique_ptr<Daq> {
         const auto addr = comedi::parse_address(a);
         return std::make_unique<comedi::Driver>(comedi::open_comedilib_board(addr.device), addr);
       }});
  r.set_simulated_twin("keysight33500",
                       "measure --instrument sim; sim-instrument --dialect keysight");
  r.set_simulated_twin(
      "tektronix_awg",
      "measure --instrument 'sim?awg=tektronix'; sim-instrument --dialect tektronix");
  r.set_simulated_twin("infiniium", "measure --instrument sim; sim-instrument (the DAQ on PORT+1)");
  r.set_simulated_twin("redpitaya", "sim-instrument --dialect redpitaya");
  r.set_simulated_twin(
      "comedi",
      "measure --instrument sim --adc-bits 12 --daq 'comedi-sim:///dev/comedi0' (a PCI-6110 twin)");
  // What the GUI's "Use" fills in: the embedded bench's AWG dialects and its
  // Infiniium run in process ("sim"); a board DAQ its default address.
  r.set_use_addresses("keysight33500", "sim", "");
  r.set_use_addresses("tektronix_awg", "sim?awg=tektronix", "");
  r.set_use_addresses("infiniium", "sim", "");
  r.set_use_addresses("comedi", "", comedi::Address{}.to_string());
}

std::vector<DriverFamily> list_families(const DriverRegistry& r) {
  std::vector<DriverFamily> out;
  auto family = [&](const std::string& key, const std::string& description, std::vector<std::string> roles,
                    std::string chosen_by, std::string address_form) {
    auto [awg, daq] = r.use_addresses(key);
    out.push_back({key, description, std::move(roles), std::move(chosen_by), std::move(address_form),
                   r.simulated_twin(key), std::move(awg), std::move(daq)});
  };
  for (const auto& e : r.awgs()) family(e.key, e.description, {"awg"}, "*IDN?", "");
  for (const auto& e : r.daqs()) family(e.key, e.description, {"daq"}, "*IDN?", "");
  for (const auto& e : r.duals()) family(e.key, e.description, {"awg", "daq"}, "*IDN?", "");
  for (const auto& e : r.board_daqs()) family(e.key, e.description, {"daq"}, "address", e.address_form);
  return out;
}

std::string family_table_markdown(const DriverRegistry& r) {
  auto cell = [](std::string& out, const std::string& text) {  // a '|' would end the table's cell
    for (char c : text) {
      if (c == '|') out += '\\';
      out += c;
    }
  };
  std::string out = "| key | roles | chosen by | what it is | simulated twin |\n| --- | --- | --- | --- | --- |\n";
  for (const auto& f : list_families(r)) {
    out += "| `";
    out += f.key;
    out += "` | ";
    for (std::size_t k = 0; k < f.roles.size(); ++k) {
      if (k) out += '+';
      out += f.roles[k];
    }
    out += " | ";
    if (f.chosen_by == "address") {
      out += "its address `";
      cell(out, f.address_form);
      out += '`';
    } else {
      out += "`*IDN?`";
    }
    out += " | ";
    cell(out, f.description);
    out += " | ";
    if (f.simulated_twin.empty()) {
      out += '-';
    } else {
      out += '`';
      cell(out, f.simulated_twin);
      out += '`';
    }
    out += " |\n";
  }
  return out;
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
