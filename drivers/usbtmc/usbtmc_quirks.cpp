#include "drivers/usbtmc/usbtmc_quirks.hpp"

#include <array>

namespace piezo::drivers::usbtmc {

namespace {
// Sources:
//  [linux]  drivers/usb/class/usbtmc.c (e.g. v3.16), usbtmc_id_quirk[] =
//           {1ab1:0588, 1ab1:04b0}, setting rigol_quirk: usbtmc_read() then
//           sends one REQUEST_DEV_DEP_MSG_IN for the whole read and parses
//           the header in the first bulk-IN read only.
//  [pyusbtmc] python-ivi/python-usbtmc, RIGOL_QUIRK_PIDS = [0x04ce, 0x0588].
//  [sigrok] libsigrok src/scpi/scpi_usbtmc_libusb.c notes that the Agilent
//           DSO1000 series (0957:0588) is a rebadged Rigol DS1000; that it
//           shares this quirk is our inference from the shared firmware.
constexpr std::array kQuirks{
    UsbTmcQuirk{0x1ab1, 0x0588, "Rigol DS1000 series", true, "[linux] [pyusbtmc]"},
    UsbTmcQuirk{0x1ab1, 0x04b0, "Rigol DS2000 series", true, "[linux]"},
    UsbTmcQuirk{0x1ab1, 0x04ce, "Rigol DS1000Z series", true, "[pyusbtmc]"},
    UsbTmcQuirk{0x0957, 0x0588, "Agilent DSO1000 (rebadged Rigol DS1000)", true,
                "[sigrok] rebadge note; inferred from 1ab1:0588"},
};
}  // namespace

std::span<const UsbTmcQuirk> quirk_table() { return kQuirks; }

const UsbTmcQuirk* find_quirk(std::uint16_t vid, std::uint16_t pid) {
  for (const UsbTmcQuirk& q : kQuirks)
    if (q.vid == vid && q.pid == pid) return &q;
  return nullptr;
}

}  // namespace piezo::drivers::usbtmc
