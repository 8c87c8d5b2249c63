// SCPI plumbing: definite-length blocks, server-side framing and header
// matching, the client's query/block/error-queue discipline over a loopback.
#include <gtest/gtest.h>

#include "drivers/ieee488_block.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/scpi_parse.hpp"
#include "drivers/sim/loopback_transport.hpp"

using namespace piezo::drivers;

TEST(Ieee488Block, HeaderAndParse) {
  EXPECT_EQ(block_header(0), "#10");
  EXPECT_EQ(block_header(40000), "#540000");
  std::vector<std::uint8_t> data = {'#', '2', '1', '2'};
  auto h = parse_block_header(data);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->header_len, 4u);
  EXPECT_EQ(h->payload_len, 12u);
  std::vector<std::uint8_t> partial = {'#', '3', '1'};
  EXPECT_FALSE(parse_block_header(partial));
  std::vector<std::uint8_t> bad = {'#', 'X'};
  EXPECT_THROW(parse_block_header(bad), std::invalid_argument);
  std::vector<std::uint8_t> indefinite = {'#', '0'};
  EXPECT_THROW(parse_block_header(indefinite), std::invalid_argument);
  std::vector<std::uint8_t> nondigit = {'#', '2', '1', 'a'};
  EXPECT_THROW(parse_block_header(nondigit), std::invalid_argument);
}

TEST(ScpiParse, HeaderMatchingShortLongOptionalSuffix) {
  using scpi::match;
  EXPECT_TRUE(match("[SOURce#:]FUNCtion:ARBitrary:SRATe", "SOUR1:FUNC:ARB:SRAT"));
  EXPECT_TRUE(match("[SOURce#:]FUNCtion:ARBitrary:SRATe", "function:arbitrary:srate"));
  EXPECT_FALSE(match("[SOURce#:]FUNCtion:ARBitrary:SRATe", "SOUR1:FUNC:ARB"));
  EXPECT_FALSE(match("[SOURce#:]FUNCtion", "SOUR1:FUNCT"));  // neither short nor long
  std::vector<int> sfx;
  EXPECT_TRUE(match("CHANnel#:RANGe", "CHAN2:RANG", &sfx));
  ASSERT_EQ(sfx.size(), 1u);
  EXPECT_EQ(sfx[0], 2);
  EXPECT_TRUE(match("SYSTem:ERRor[:NEXT]", "SYST:ERR"));
  auto c = scpi::parse_command(":ACQ:SRAT:ANAL? ");
  EXPECT_TRUE(c.query);
  EXPECT_EQ(c.header, "ACQ:SRAT:ANAL");
  auto d = scpi::parse_command("SOUR1:DATA:ARB PIEZO,");
  ASSERT_EQ(d.params.size(), 2u);
  EXPECT_EQ(d.params[0], "PIEZO");
}

TEST(ScpiParse, FramerKeepsNewlinesInsideBlocks) {
  scpi::InputFramer f;
  std::string a = "*IDN?\nDATA:ARB X,#15a\nb\nc\n*OPC?";
  f.feed(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(a.data()), a.size()));
  auto m1 = f.next();
  ASSERT_TRUE(m1);
  EXPECT_EQ(m1->text, "*IDN?");
  auto m2 = f.next();
  ASSERT_TRUE(m2);
  EXPECT_TRUE(m2->has_block);
  EXPECT_EQ(std::string(m2->block.begin(), m2->block.end()), "a\nb\nc");
  EXPECT_FALSE(f.next());  // "*OPC?" has no terminator yet
  std::string rest = "\n";
  f.feed(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(rest.data()), 1));
  auto m3 = f.next();
  ASSERT_TRUE(m3);
  EXPECT_EQ(m3->text, "*OPC?");
}

namespace {
// A minimal device: answers VAL? with a number, BLK? with a block, ERR makes an error.
class EchoDevice : public sim::ScpiDevice {
 protected:
  std::string idn() const override { return "ACME,ECHO,1,0"; }
  bool command(const scpi::Command& c, const scpi::ProgramMessage&, sim::Reply& out) override {
    if (c.header == "VAL" && c.query) append(out, "+1.25E+03\n");
    else if (c.header == "BLK" && c.query) append(out, "#14abcd\n");
    else if (c.header == "TEXT" && c.query) append(out, "hello\n");
    else if (c.header == "ERR") push_error(-222, "Data out of range");
    else if (c.header == "OK") {}
    else return false;
    return true;
  }
};
ScpiClient echo_client() {
  return ScpiClient(std::make_unique<sim::LoopbackTransport>(std::make_shared<EchoDevice>(), "loop://echo"));
}
}  // namespace

TEST(ScpiClient, QueriesBlocksAndTheErrorQueue) {
  auto c = echo_client();
  EXPECT_EQ(c.identify(), "ACME,ECHO,1,0");
  EXPECT_DOUBLE_EQ(c.query_double("VAL?"), 1250.0);
  auto b = c.query_block("BLK?");
  EXPECT_EQ(std::string(b.begin(), b.end()), "abcd");
  EXPECT_EQ(c.query("TEXT?"), "hello");  // the block's terminator was consumed
  EXPECT_NO_THROW(c.configure("OK"));
  try {
    c.configure("ERR");
    FAIL() << "configure accepted an instrument error";
  } catch (const InstrumentError& e) {
    EXPECT_NE(std::string(e.what()).find("-222"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("'ERR'"), std::string::npos);
  }
  EXPECT_THROW(c.configure("NOSUCH"), InstrumentError);  // -113 undefined header
  EXPECT_THROW(c.query_double("TEXT?"), InstrumentError);
  EXPECT_THROW(c.query("OK"), TransportError);  // no reply: timeout
}
