#include <gtest/gtest.h>

#include "drivers/instrument_uri.hpp"

using piezo::drivers::InstrumentUri;
using piezo::drivers::parse_instrument_uri;

TEST(InstrumentUri, ParsesTheThreeForms) {
  EXPECT_EQ(parse_instrument_uri("sim").kind, InstrumentUri::Kind::Sim);
  auto t = parse_instrument_uri("tcp://127.0.0.1:5025");
  EXPECT_EQ(t.kind, InstrumentUri::Kind::Tcp);
  EXPECT_EQ(t.host, "127.0.0.1");
  EXPECT_EQ(t.port, 5025);
  auto u = parse_instrument_uri("usbtmc://0957:2807/MY1234");
  EXPECT_EQ(u.kind, InstrumentUri::Kind::UsbTmc);
  EXPECT_EQ(u.vid, 0x0957);
  EXPECT_EQ(u.pid, 0x2807);
  EXPECT_EQ(u.serial, "MY1234");
  EXPECT_EQ(u.to_string(), "usbtmc://0957:2807/MY1234");
  EXPECT_EQ(parse_instrument_uri("usbtmc://0x1ab1:0x0642").pid, 0x0642);
}

TEST(InstrumentUri, RefusesMalformedAddresses) {
  for (const char* bad : {"", "tcp://", "tcp://host", "tcp://host:0", "tcp://host:70000",
                          "tcp://:5025", "usbtmc://xyz:1", "usbtmc://1234", "usbtmc://1:2/",
                          "gpib://1", "usbtmc://12345:1"})
    EXPECT_THROW(parse_instrument_uri(bad), std::invalid_argument) << bad;
}
