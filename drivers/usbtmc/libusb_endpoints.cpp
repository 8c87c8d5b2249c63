#include "drivers/usbtmc/libusb_endpoints.hpp"

#include <libusb.h>

#include <cstdio>
#include <vector>

#include "drivers/transport.hpp"

namespace piezo::drivers::usbtmc {

namespace {
std::string vidpid(std::uint16_t vid, std::uint16_t pid) {
  char b[16];
  std::snprintf(b, sizeof b, "%04x:%04x", vid, pid);
  return b;
}

unsigned int ms(std::chrono::milliseconds t) {
  return t.count() <= 0 ? 1u : static_cast<unsigned int>(t.count());  // libusb: 0 = forever
}

UsbIoError usb_error(int rc, const char* what) {
  using C = UsbIoError::Code;
  const C c = rc == LIBUSB_ERROR_TIMEOUT     ? C::Timeout
              : rc == LIBUSB_ERROR_PIPE      ? C::Stall
              : rc == LIBUSB_ERROR_NO_DEVICE ? C::NoDevice
                                             : C::Io;
  return UsbIoError(c, std::string(what) + ": " + libusb_error_name(rc));
}

struct DeviceList {
  libusb_device** list = nullptr;
  ssize_t count = 0;
  ~DeviceList() {
    if (list) libusb_free_device_list(list, 1);
  }
};

struct ConfigDescriptor {
  libusb_config_descriptor* desc = nullptr;
  ~ConfigDescriptor() {
    if (desc) libusb_free_config_descriptor(desc);
  }
};
}  // namespace

struct LibusbEndpoints::Impl {
  libusb_context* ctx = nullptr;
  libusb_device_handle* handle = nullptr;
  std::uint8_t interface = 0;
  std::uint8_t ep_out = 0, ep_in = 0;
  std::size_t max_packet = 0;
  bool claimed = false;
  bool reattach = false;

  ~Impl() {
    if (handle) {
      if (claimed) libusb_release_interface(handle, interface);
      if (reattach) libusb_attach_kernel_driver(handle, interface);
      libusb_close(handle);
    }
    if (ctx) libusb_exit(ctx);
  }
};

LibusbEndpoints::LibusbEndpoints(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LibusbEndpoints::~LibusbEndpoints() = default;

std::unique_ptr<LibusbEndpoints> LibusbEndpoints::open(std::uint16_t vid, std::uint16_t pid,
                                                       const std::optional<std::string>& serial,
                                                       const std::string& address) {
  auto fail = [&](TransportError::Kind k, const std::string& what) -> TransportError {
    return TransportError(k, address + ": " + what);
  };
  using K = TransportError::Kind;
  auto impl = std::make_unique<Impl>();
  if (int rc = libusb_init(&impl->ctx); rc != 0) {
    impl->ctx = nullptr;
    throw fail(K::Io, std::string("cannot initialise libusb: ") + libusb_error_name(rc));
  }

  DeviceList devs;
  devs.count = libusb_get_device_list(impl->ctx, &devs.list);
  if (devs.count < 0)
    throw fail(K::Io, std::string("cannot list USB devices: ") +
                          libusb_error_name(static_cast<int>(devs.count)));

  // Candidates by VID:PID; with a serial, open each to read iSerialNumber.
  std::vector<std::string> seen_serials;
  bool any = false, denied = false;
  for (ssize_t i = 0; i < devs.count && !impl->handle; ++i) {
    libusb_device_descriptor dd{};
    if (libusb_get_device_descriptor(devs.list[i], &dd) != 0) continue;
    if (dd.idVendor != vid || dd.idProduct != pid) continue;
    any = true;
    libusb_device_handle* h = nullptr;
    if (int rc = libusb_open(devs.list[i], &h); rc != 0) {
      if (rc == LIBUSB_ERROR_ACCESS) denied = true;
      continue;
    }
    if (serial) {
      unsigned char buf[256] = {};
      int n = dd.iSerialNumber
                  ? libusb_get_string_descriptor_ascii(h, dd.iSerialNumber, buf, sizeof buf)
                  : LIBUSB_ERROR_NOT_FOUND;
      std::string s = n > 0 ? std::string(reinterpret_cast<char*>(buf), static_cast<std::size_t>(n))
                            : std::string("(none)");
      if (s != *serial) {
        seen_serials.push_back(s);
        libusb_close(h);
        continue;
      }
    }
    impl->handle = h;
  }
  if (!impl->handle) {
    if (!any) throw fail(K::Io, "no USB device " + vidpid(vid, pid));
    if (denied && seen_serials.empty())
      throw fail(K::Io, "permission denied opening USB device " + vidpid(vid, pid) +
                            ": add a udev rule, e.g. SUBSYSTEM==\"usb\", ATTRS{idVendor}==\"" +
                            vidpid(vid, pid).substr(0, 4) + "\", ATTRS{idProduct}==\"" +
                            vidpid(vid, pid).substr(5) +
                            "\", MODE=\"0660\", GROUP=\"plugdev\" (then replug)");
    std::string found;
    for (const auto& s : seen_serials) found += (found.empty() ? "" : ", ") + s;
    if (denied) found += (found.empty() ? "" : ", ") + std::string("(others: permission denied)");
    throw fail(K::Io, "serial " + *serial + " not found for " + vidpid(vid, pid) +
                          "; found: " + (found.empty() ? "none" : found));
  }

  // The USBTMC interface and its bulk endpoints, in the active configuration.
  libusb_device* dev = libusb_get_device(impl->handle);
  ConfigDescriptor cfg;
  if (int rc = libusb_get_active_config_descriptor(dev, &cfg.desc); rc != 0)
    throw fail(K::Io,
               std::string("cannot read the configuration descriptor: ") + libusb_error_name(rc));
  bool found = false;
  for (int i = 0; i < cfg.desc->bNumInterfaces && !found; ++i) {
    const libusb_interface& itf = cfg.desc->interface[i];
    if (itf.num_altsetting < 1) continue;
    const libusb_interface_descriptor& alt = itf.altsetting[0];
    if (alt.bInterfaceClass != kInterfaceClass || alt.bInterfaceSubClass != kInterfaceSubClass)
      continue;
    impl->interface = alt.bInterfaceNumber;
    for (int e = 0; e < alt.bNumEndpoints; ++e) {
      const libusb_endpoint_descriptor& ed = alt.endpoint[e];
      if ((ed.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
      if (ed.bEndpointAddress & LIBUSB_ENDPOINT_IN) {
        impl->ep_in = ed.bEndpointAddress;
        impl->max_packet = ed.wMaxPacketSize & 0x7FF;
      } else {
        impl->ep_out = ed.bEndpointAddress;
      }
    }
    found = impl->ep_in && impl->ep_out && impl->max_packet;
  }
  if (!found)
    throw fail(K::Io,
               "USB device " + vidpid(vid, pid) +
                   " has no USBTMC interface (class 0xFE subclass 0x03) with bulk endpoints");

  if (libusb_kernel_driver_active(impl->handle, impl->interface) == 1) {
    if (int rc = libusb_detach_kernel_driver(impl->handle, impl->interface); rc != 0)
      throw fail(K::Io,
                 std::string("cannot detach the kernel driver (usbtmc): ") + libusb_error_name(rc));
    impl->reattach = true;
  }
  if (int rc = libusb_claim_interface(impl->handle, impl->interface); rc != 0)
    throw fail(K::Io, std::string("cannot claim the USBTMC interface") +
                          (rc == LIBUSB_ERROR_BUSY ? " (in use by another program)" : "") + ": " +
                          libusb_error_name(rc));
  impl->claimed = true;
  return std::unique_ptr<LibusbEndpoints>(new LibusbEndpoints(std::move(impl)));
}

std::uint8_t LibusbEndpoints::interface_number() const { return impl_->interface; }
std::uint8_t LibusbEndpoints::bulk_out_address() const { return impl_->ep_out; }
std::uint8_t LibusbEndpoints::bulk_in_address() const { return impl_->ep_in; }
std::size_t LibusbEndpoints::max_packet_size() const { return impl_->max_packet; }

void LibusbEndpoints::bulk_out(std::span<const std::uint8_t> bytes,
                               std::chrono::milliseconds timeout) {
  int done = 0;
  // libusb takes a non-const buffer for both directions; OUT does not write it.
  const int rc =
      libusb_bulk_transfer(impl_->handle, impl_->ep_out, const_cast<unsigned char*>(bytes.data()),
                           static_cast<int>(bytes.size()), &done, ms(timeout));
  if (rc != 0) throw usb_error(rc, "bulk-OUT");
  if (static_cast<std::size_t>(done) != bytes.size())
    throw UsbIoError(UsbIoError::Code::Io, "bulk-OUT: short write");
}

std::size_t LibusbEndpoints::bulk_in(std::uint8_t* buf, std::size_t max,
                                     std::chrono::milliseconds timeout) {
  int done = 0;
  const int rc = libusb_bulk_transfer(impl_->handle, impl_->ep_in, buf, static_cast<int>(max),
                                      &done, ms(timeout));
  if (rc != 0) throw usb_error(rc, "bulk-IN");
  return static_cast<std::size_t>(done);
}

std::size_t LibusbEndpoints::control_in(const ControlSetup& s, std::uint8_t* buf,
                                        std::chrono::milliseconds timeout) {
  const int rc = libusb_control_transfer(impl_->handle, s.request_type, s.request, s.value, s.index,
                                         buf, s.length, ms(timeout));
  if (rc < 0) throw usb_error(rc, "control request");
  return static_cast<std::size_t>(rc);
}

void LibusbEndpoints::clear_halt(std::uint8_t endpoint) {
  if (int rc = libusb_clear_halt(impl_->handle, endpoint); rc != 0)
    throw usb_error(rc, "clear halt");
}

}  // namespace piezo::drivers::usbtmc
