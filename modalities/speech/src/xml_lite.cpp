#include "xml_lite.hpp"

#include <cctype>

namespace dreamsense::speech::xml {
namespace {

class Reader {
 public:
  Reader(const std::string& s, const std::string& source) : s_(s), source_(source) {}

  Result<Node> document() {
    Node root;
    bool have_root = false;
    while (true) {
      skip_space();
      if (eof()) break;
      if (starts("<?")) {
        if (auto st = skip_until("?>", "processing instruction"); !st)
          return tl::unexpected(st.error());
      } else if (starts("<!--")) {
        if (auto st = skip_until("-->", "comment"); !st) return tl::unexpected(st.error());
      } else if (starts("<!DOCTYPE")) {
        if (auto st = skip_until(">", "DOCTYPE"); !st) return tl::unexpected(st.error());
      } else if (peek() == '<') {
        if (have_root) return err(line_, "more than one root element");
        auto e = element();
        if (!e) return e;
        root = std::move(*e);
        have_root = true;
      } else {
        return err(line_, "text outside the root element");
      }
    }
    if (!have_root) return err(line_, "no root element");
    return root;
  }

 private:
  bool eof() const { return pos_ >= s_.size(); }
  char peek() const { return eof() ? '\0' : s_[pos_]; }
  bool starts(const char* p) const {
    return s_.compare(pos_, std::char_traits<char>::length(p), p) == 0;
  }
  void advance(size_t n = 1) {
    for (size_t i = 0; i < n && !eof(); ++i, ++pos_)
      if (s_[pos_] == '\n') ++line_;
  }
  void skip_space() {
    while (!eof() && std::isspace(static_cast<unsigned char>(peek()))) advance();
  }
  tl::unexpected<Error> err(int line, const std::string& what) const {
    return make_error(ErrorCode::kCorruptData, "{}:{}: {}", source_, line, what);
  }
  Status skip_until(const char* end, const char* what) {
    const int start = line_;
    const size_t at = s_.find(end, pos_);
    if (at == std::string::npos) return err(start, std::string("unterminated ") + what);
    advance(at + std::char_traits<char>::length(end) - pos_);
    return ok_status();
  }
  static bool name_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' ||
           c == ':';
  }
  std::string name() {
    std::string n;
    while (!eof() && name_char(peek())) {
      n += peek();
      advance();
    }
    return n;
  }
  Result<std::string> decode(const std::string& raw, int line) const {
    std::string out;
    for (size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] != '&') {
        out += raw[i];
        continue;
      }
      const size_t semi = raw.find(';', i);
      if (semi == std::string::npos) return err(line, "unterminated entity reference");
      const std::string ent = raw.substr(i + 1, semi - i - 1);
      if (ent == "amp")
        out += '&';
      else if (ent == "lt")
        out += '<';
      else if (ent == "gt")
        out += '>';
      else if (ent == "quot")
        out += '"';
      else if (ent == "apos")
        out += '\'';
      else if (!ent.empty() && ent[0] == '#') {
        long code = 0;
        try {
          code = ent.size() > 1 && (ent[1] == 'x' || ent[1] == 'X')
                     ? std::stol(ent.substr(2), nullptr, 16)
                     : std::stol(ent.substr(1));
        } catch (...) {
          return err(line, "bad character reference &" + ent + ";");
        }
        if (code < 0x80)
          out += static_cast<char>(code);
        else if (code < 0x800) {
          out += static_cast<char>(0xC0 | (code >> 6));
          out += static_cast<char>(0x80 | (code & 0x3F));
        } else {
          out += static_cast<char>(0xE0 | (code >> 12));
          out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
          out += static_cast<char>(0x80 | (code & 0x3F));
        }
      } else {
        return err(line, "unknown entity &" + ent + ";");
      }
      i = semi;
    }
    return out;
  }

  Result<Node> element() {
    Node e;
    e.line = line_;
    advance();  // '<'
    e.name = name();
    if (e.name.empty()) return err(line_, "expected an element name after '<'");
    while (true) {
      skip_space();
      if (eof()) return err(e.line, "unterminated start tag <" + e.name + ">");
      if (starts("/>")) {
        advance(2);
        return e;
      }
      if (peek() == '>') {
        advance();
        break;
      }
      const int aline = line_;
      std::string an = name();
      if (an.empty())
        return err(line_, std::string("unexpected '") + peek() + "' in tag <" + e.name + ">");
      skip_space();
      if (peek() != '=') return err(aline, "attribute " + an + " of <" + e.name + "> has no value");
      advance();
      skip_space();
      const char q = peek();
      if (q != '"' && q != '\'') return err(aline, "attribute " + an + " value must be quoted");
      advance();
      const size_t end = s_.find(q, pos_);
      if (end == std::string::npos) return err(aline, "unterminated value of attribute " + an);
      auto v = decode(s_.substr(pos_, end - pos_), aline);
      if (!v) return tl::unexpected(v.error());
      advance(end + 1 - pos_);
      if (e.attributes.count(an)) return err(aline, "duplicate attribute " + an);
      e.attributes[an] = *v;
    }
    // Content.
    while (true) {
      if (eof()) return err(e.line, "element <" + e.name + "> is never closed");
      if (starts("</")) {
        const int cline = line_;
        advance(2);
        const std::string n = name();
        skip_space();
        if (peek() != '>') return err(cline, "malformed end tag </" + n);
        advance();
        if (n != e.name)
          return err(cline, "end tag </" + n + "> does not match <" + e.name + "> opened on line " +
                                std::to_string(e.line));
        return e;
      }
      if (starts("<!--")) {
        if (auto st = skip_until("-->", "comment"); !st) return tl::unexpected(st.error());
      } else if (starts("<![CDATA[")) {
        const int tline = line_;
        advance(9);
        const size_t end = s_.find("]]>", pos_);
        if (end == std::string::npos) return err(tline, "unterminated CDATA section");
        Node t;
        t.is_text = true;
        t.line = tline;
        t.text = s_.substr(pos_, end - pos_);
        advance(end + 3 - pos_);
        e.children.push_back(std::move(t));
      } else if (starts("<?")) {
        if (auto st = skip_until("?>", "processing instruction"); !st)
          return tl::unexpected(st.error());
      } else if (peek() == '<') {
        auto c = element();
        if (!c) return c;
        e.children.push_back(std::move(*c));
      } else {
        const int tline = line_;
        const size_t end = s_.find('<', pos_);
        const size_t stop = end == std::string::npos ? s_.size() : end;
        auto v = decode(s_.substr(pos_, stop - pos_), tline);
        if (!v) return tl::unexpected(v.error());
        advance(stop - pos_);
        Node t;
        t.is_text = true;
        t.line = tline;
        t.text = *v;
        e.children.push_back(std::move(t));
      }
    }
  }

  const std::string& s_;
  const std::string& source_;
  size_t pos_ = 0;
  int line_ = 1;
};

}  // namespace

Result<Node> parse(const std::string& text, const std::string& source) {
  return Reader(text, source).document();
}

}  // namespace dreamsense::speech::xml
