#include "drivers/scpi_parse.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
#include <stdexcept>

#include "drivers/ieee488_block.hpp"

namespace piezo::drivers::scpi {

void InputFramer::feed(std::span<const std::uint8_t> bytes) {
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
}

std::optional<ProgramMessage> InputFramer::next() {
  // Scan for '\n' outside a binary block, from where the last call stopped.
  std::size_t& i = scan_;
  while (i < buf_.size()) {
    const std::uint8_t c = buf_[i];
    if (quote_) {  // '#' inside a string is text; a newline still ends the message
      if (c == quote_) quote_ = 0;
      if (c != '\n') {
        ++i;
        continue;
      }
    } else if (c == '"' || c == '\'') {
      quote_ = static_cast<char>(c);
      ++i;
      continue;
    }
    if (c == '#' && !quote_) {
      if (i + 1 >= buf_.size()) return std::nullopt;  // block or text: the next byte decides
      std::optional<BlockHeader> h;
      const std::uint8_t n = buf_[i + 1];
      if (n >= '1' && n <= '9') {
        try {
          h = parse_block_header(std::span<const std::uint8_t>(buf_).subspan(i));
          if (!h) return std::nullopt;  // need more bytes of the header
        } catch (const std::invalid_argument&) {
          h.reset();  // "#2x..": not a block header; the '#' is text
        }
      }
      if (h) {
        const std::size_t end = i + h->header_len + h->payload_len;
        if (buf_.size() < end) return std::nullopt;
        // the terminator follows the block
        std::size_t stop = end;
        while (stop < buf_.size() && buf_[stop] != '\n') ++stop;
        if (stop == buf_.size()) return std::nullopt;
        ProgramMessage m;
        m.text.assign(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(i));
        m.block.assign(buf_.begin() + static_cast<std::ptrdiff_t>(i + h->header_len),
                       buf_.begin() + static_cast<std::ptrdiff_t>(end));
        m.has_block = true;
        buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(stop + 1));
        i = 0;
        quote_ = 0;
        return m;
      }
    }
    if (c == '\n') {
      ProgramMessage m;
      m.text.assign(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(i));
      if (!m.text.empty() && m.text.back() == '\r') m.text.pop_back();
      buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(i + 1));
      i = 0;
      quote_ = 0;
      return m;
    }
    ++i;
  }
  return std::nullopt;
}

namespace {
std::string trim(const std::string& s) {
  auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}
std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}
std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (char c : s) {
    if (c == '"') quoted = !quoted;
    if (c == sep && !quoted) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}
}  // namespace

std::vector<std::string> split_commands(const std::string& text) {
  std::vector<std::string> out;
  for (auto& part : split(text, ';')) {
    auto t = trim(part);
    if (!t.empty()) out.push_back(t);
  }
  return out;
}

Command parse_command(const std::string& text) {
  Command c;
  std::string t = trim(text);
  auto sp = t.find_first_of(" \t");
  std::string hdr = sp == std::string::npos ? t : t.substr(0, sp);
  std::string rest = sp == std::string::npos ? "" : trim(t.substr(sp + 1));
  if (!hdr.empty() && hdr.front() == ':') hdr.erase(0, 1);
  if (!hdr.empty() && hdr.back() == '?') {
    c.query = true;
    hdr.pop_back();
  }
  c.header = hdr;
  if (!rest.empty())
    for (auto& p : split(rest, ',')) c.params.push_back(trim(p));
  return c;
}

namespace {
struct Node {
  std::string long_form;  // upper-cased
  std::string short_form;  // upper-case letters of the pattern
  bool optional = false;
  bool suffix = false;
};

std::vector<Node> parse_pattern(const std::string& pattern) {
  std::vector<Node> nodes;
  std::string p = pattern;
  if (!p.empty() && p.front() == ':') p.erase(0, 1);
  std::size_t i = 0;
  while (i < p.size()) {
    Node n;
    if (p[i] == '[') {
      n.optional = true;
      ++i;
      if (i < p.size() && p[i] == ':') ++i;  // "[:NEXT]"
    }
    std::string word;
    while (i < p.size() && p[i] != ':' && p[i] != ']' && p[i] != '[') word += p[i++];
    while (i < p.size() && (p[i] == ':' || p[i] == ']')) ++i;  // "[SOURce#:]" and "NODE:"
    if (!word.empty() && word.back() == '#') {
      n.suffix = true;
      word.pop_back();
    }
    for (char c : word)
      if (std::isupper(static_cast<unsigned char>(c))) n.short_form += c;
    n.long_form = upper(word);
    nodes.push_back(n);
  }
  return nodes;
}

bool match_nodes(const std::vector<Node>& nodes, std::size_t ni, const std::vector<std::string>& segs,
                 std::size_t si, std::vector<int>* suffixes) {
  if (ni == nodes.size()) return si == segs.size();
  const Node& n = nodes[ni];
  if (si < segs.size()) {
    std::string s = upper(segs[si]);
    int suffix = 1;
    if (n.suffix) {
      std::size_t d = s.size();
      while (d > 0 && std::isdigit(static_cast<unsigned char>(s[d - 1]))) --d;
      if (d < s.size()) {
        long long v = 0;
        for (std::size_t k = d; k < s.size(); ++k) {
          v = v * 10 + (s[k] - '0');
          if (v > std::numeric_limits<int>::max()) return false;  // no such suffix
        }
        suffix = static_cast<int>(v);
      }
      s = s.substr(0, d);
    }
    if (s == n.long_form || s == n.short_form) {
      std::size_t before = suffixes ? suffixes->size() : 0;
      if (suffixes && n.suffix) suffixes->push_back(suffix);
      if (match_nodes(nodes, ni + 1, segs, si + 1, suffixes)) return true;
      if (suffixes) suffixes->resize(before);
    }
  }
  if (n.optional) {
    std::size_t before = suffixes ? suffixes->size() : 0;
    if (suffixes && n.suffix) suffixes->push_back(1);
    if (match_nodes(nodes, ni + 1, segs, si, suffixes)) return true;
    if (suffixes) suffixes->resize(before);
  }
  return false;
}
}  // namespace

bool match(const std::string& pattern, const std::string& header, std::vector<int>* suffixes) {
  auto nodes = parse_pattern(pattern);
  std::string h = header;
  if (!h.empty() && h.front() == ':') h.erase(0, 1);
  auto segs = split(h, ':');
  return match_nodes(nodes, 0, segs, 0, suffixes);
}

}  // namespace piezo::drivers::scpi
