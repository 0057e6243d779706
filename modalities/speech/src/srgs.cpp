#include "dreamsense/speech/srgs.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "xml_dom.hpp"

namespace dreamsense::speech {
namespace {

using Kind = SrgsNode::Kind;

std::string local_name(const std::string& n) {
  const size_t colon = n.find(':');
  return colon == std::string::npos ? n : n.substr(colon + 1);
}

std::string trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

class Builder {
 public:
  explicit Builder(const std::string& source) : source_(source) {}

  tl::unexpected<Error> err(int line, const std::string& what) const {
    return make_error(ErrorCode::kCorruptData, "{}:{}: {}", source_, line, what);
  }

  Status parse_repeat(const std::string& r, int line, SrgsNode& n) const {
    const std::string v = trim(r);
    auto number = [&](const std::string& s, int& out) {
      // At most 6 digits: std::stoi throws on numbers beyond int (found by fuzz_grammar).
      if (s.empty() || s.size() > 6 || !std::all_of(s.begin(), s.end(), [](char c) {
            return std::isdigit(static_cast<unsigned char>(c));
          }))
        return false;
      out = std::stoi(s);
      return true;
    };
    const size_t dash = v.find('-');
    int lo = 0, hi = 0;
    if (dash == std::string::npos) {
      if (!number(v, lo)) return err(line, "bad repeat=\"" + r + "\" (expected n, m-n or m-)");
      hi = lo;
    } else {
      if (!number(v.substr(0, dash), lo))
        return err(line, "bad repeat=\"" + r + "\" (expected n, m-n or m-)");
      const std::string rest = v.substr(dash + 1);
      if (rest.empty())
        hi = -1;
      else if (!number(rest, hi))
        return err(line, "bad repeat=\"" + r + "\" (expected n, m-n or m-)");
    }
    if (hi != -1 && hi < lo) return err(line, "repeat=\"" + r + "\" has max < min");
    n.min_repeat = lo;
    n.max_repeat = hi;
    return ok_status();
  }

  // An <item> (in a sequence or a <one-of>): a sequence with an optional repeat.
  Status parse_item(const xml::Node& element, SrgsNode& item) {
    item.kind = Kind::kSequence;
    item.line = element.line;
    if (auto it = element.attributes.find("repeat"); it != element.attributes.end())
      if (auto st = parse_repeat(it->second, element.line, item); !st) return st;
    return content(element, item);
  }

  // Appends the nodes for an element's content to `seq` (a kSequence).
  Status content(const xml::Node& parent, SrgsNode& seq) {
    for (const auto& c : parent.children) {
      if (c.is_text) {
        std::istringstream in(c.text);
        std::string w;
        while (in >> w) seq.children.push_back(token(w, c.line));
        continue;
      }
      const std::string n = local_name(c.name);
      if (n == "item") {
        SrgsNode item;
        if (auto st = parse_item(c, item); !st) return st;
        seq.children.push_back(std::move(item));
      } else if (n == "one-of") {
        SrgsNode alt;
        alt.kind = Kind::kOneOf;
        alt.line = c.line;
        for (const auto& i : c.children) {
          if (i.is_text) {
            if (!trim(i.text).empty())
              return err(i.line, "text directly inside <one-of> (wrap it in <item>)");
            continue;
          }
          if (local_name(i.name) != "item")
            return err(i.line, "<one-of> may contain only <item>, found <" + i.name + ">");
          SrgsNode item;
          if (auto st = parse_item(i, item); !st) return st;
          alt.children.push_back(std::move(item));
        }
        if (alt.children.empty()) return err(c.line, "empty <one-of>");
        seq.children.push_back(std::move(alt));
      } else if (n == "ruleref") {
        SrgsNode ref;
        ref.kind = Kind::kRuleRef;
        ref.line = c.line;
        if (auto sp = c.attributes.find("special"); sp != c.attributes.end()) {
          if (sp->second == "NULL") continue;  // matches nothing: an empty step
          return err(c.line, "special rule " + sp->second + " is not supported");
        }
        auto uri = c.attributes.find("uri");
        if (uri == c.attributes.end()) return err(c.line, "<ruleref> without uri");
        if (uri->second.empty() || uri->second[0] != '#')
          return err(c.line, "only local rule references (uri=\"#id\") are supported, got \"" +
                                 uri->second + "\"");
        ref.text = uri->second.substr(1);
        refs_.push_back({ref.text, c.line});
        seq.children.push_back(std::move(ref));
      } else if (n == "tag") {
        SrgsNode tag;
        tag.kind = Kind::kTag;
        tag.line = c.line;
        std::string t;
        for (const auto& x : c.children) {
          if (!x.is_text) return err(x.line, "<tag> may contain only text");
          t += x.text;
        }
        tag.text = trim(t);
        seq.children.push_back(std::move(tag));
      } else if (n == "token") {
        std::string t;
        for (const auto& x : c.children)
          if (x.is_text) t += x.text;
        std::istringstream in(t);
        std::string w;
        while (in >> w) seq.children.push_back(token(w, c.line));
      } else if (n == "example" || n == "meta" || n == "metadata" || n == "lexicon") {
        continue;
      } else {
        return err(c.line, "unsupported element <" + c.name + ">");
      }
    }
    return ok_status();
  }

  static SrgsNode token(const std::string& w, int line) {
    SrgsNode t;
    t.kind = Kind::kToken;
    t.line = line;
    for (char ch : w) t.text += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return t;
  }

  struct Ref {
    std::string id;
    int line;
  };
  std::vector<Ref> refs_;

 private:
  const std::string& source_;
};

std::string jsgf_name(const std::string& id) {
  std::string n;
  for (char c : id) n += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_';
  return n.empty() ? "rule" : n;
}

std::string jsgf_token(const std::string& w) {
  const bool plain = std::all_of(w.begin(), w.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '\'' || c == '_' || c == '-' ||
           c == '.' || static_cast<unsigned char>(c) >= 0x80;
  });
  if (plain) return w;
  std::string q = "\"";
  for (char c : w) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

// JSGF expansion of a node; empty string = matches nothing (epsilon).
std::string expr(const SrgsNode& n);

std::string sequence_once(const SrgsNode& n) {
  std::string out;
  int parts = 0;
  for (const auto& c : n.children) {
    const std::string e = expr(c);
    if (e.empty()) continue;
    if (!out.empty()) out += ' ';
    out += e;
    ++parts;
  }
  if (parts > 1) out = "(" + out + ")";
  return out;
}

std::string expr(const SrgsNode& n) {
  switch (n.kind) {
    case Kind::kToken:
      return jsgf_token(n.text);
    case Kind::kTag:
      return "";
    case Kind::kRuleRef:
      return "<" + jsgf_name(n.text) + ">";
    case Kind::kOneOf: {
      std::vector<std::string> alts;
      bool has_empty = false;
      for (const auto& c : n.children) {
        std::string e = expr(c);
        if (e.empty())
          has_empty = true;
        else
          alts.push_back(std::move(e));
      }
      if (alts.empty()) return "";
      std::string out;
      for (size_t i = 0; i < alts.size(); ++i) out += (i ? " | " : "") + alts[i];
      return has_empty ? "[" + out + "]" : "(" + out + ")";
    }
    case Kind::kSequence: {
      const std::string once = sequence_once(n);
      if (once.empty() || n.max_repeat == 0) return "";
      const int lo = n.min_repeat, hi = n.max_repeat;
      if (lo == 1 && hi == 1) return once;
      std::string out;
      if (hi == -1) {
        for (int i = 0; i + 1 < lo; ++i) out += once + " ";
        return out + once + (lo == 0 ? "*" : "+");
      }
      for (int i = 0; i < lo; ++i) out += (out.empty() ? "" : " ") + once;
      std::string opt;  // nested optionals: [a [a]] avoids ambiguous parses
      for (int i = lo; i < hi; ++i) opt = "[" + once + (opt.empty() ? "" : " " + opt) + "]";
      if (!opt.empty()) out += (out.empty() ? "" : " ") + opt;
      return out;
    }
  }
  return "";
}

}  // namespace

std::vector<std::string> split_words(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string w;
  while (in >> w) {
    for (auto& c : w) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    out.push_back(w);
  }
  return out;
}

Result<SrgsGrammar> SrgsGrammar::parse(const std::string& text, const std::string& source) {
  auto doc = xml::parse(text, source);
  if (!doc) return tl::unexpected(doc.error());
  Builder b(source);
  if (local_name(doc->name) != "grammar")
    return b.err(doc->line, "root element is <" + doc->name + ">, expected <grammar>");
  SrgsGrammar g;
  for (const auto& c : doc->children) {
    if (c.is_text) {
      if (!trim(c.text).empty()) return b.err(c.line, "text outside any <rule>");
      continue;
    }
    const std::string n = local_name(c.name);
    if (n != "rule") {
      if (n == "meta" || n == "metadata" || n == "lexicon" || n == "tag") continue;
      return b.err(c.line, "unexpected <" + c.name + "> in <grammar> (expected <rule>)");
    }
    auto id = c.attributes.find("id");
    if (id == c.attributes.end() || id->second.empty()) return b.err(c.line, "<rule> without id");
    if (g.index_.count(id->second))
      return b.err(c.line, "duplicate rule id \"" + id->second + "\"");
    SrgsRule r;
    r.id = id->second;
    auto scope = c.attributes.find("scope");
    r.is_public = scope != c.attributes.end() && scope->second == "public";
    r.body.kind = Kind::kSequence;
    r.body.line = c.line;
    if (auto st = b.content(c, r.body); !st) return tl::unexpected(st.error());
    g.index_[r.id] = g.rules_.size();
    g.rules_.push_back(std::move(r));
  }
  if (g.rules_.empty()) return b.err(doc->line, "grammar has no <rule>");
  for (const auto& ref : b.refs_)
    if (!g.index_.count(ref.id))
      return b.err(ref.line, "reference to undefined rule \"" + ref.id + "\"");
  if (auto root = doc->attributes.find("root"); root != doc->attributes.end()) {
    if (!g.index_.count(root->second))
      return b.err(doc->line, "root rule \"" + root->second + "\" is not defined");
    g.root_ = root->second;
  } else {
    auto pub = std::find_if(g.rules_.begin(), g.rules_.end(),
                            [](const SrgsRule& r) { return r.is_public; });
    g.root_ = (pub != g.rules_.end() ? *pub : g.rules_.front()).id;
  }
  // Distinct JSGF names after sanitising.
  std::set<std::string> names;
  for (const auto& r : g.rules_)
    if (!names.insert(jsgf_name(r.id)).second)
      return b.err(r.body.line, "rule ids collide once sanitised for JSGF: \"" + r.id + "\"");
  return g;
}

Result<SrgsGrammar> SrgsGrammar::parse_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kNotFound, "cannot open SRGS grammar {}", path.string());
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path.string());
}

std::string SrgsGrammar::to_jsgf(const std::string& grammar_name) const {
  std::string out = "#JSGF V1.0;\n\ngrammar " + jsgf_name(grammar_name) + ";\n\n";
  auto body = [](const SrgsRule& r) {
    std::string e = expr(r.body);
    return e.empty() ? std::string("<NULL>") : e;
  };
  const SrgsRule& root = rules_[index_.at(root_)];
  out += "public <" + jsgf_name(root.id) + "> = " + body(root) + ";\n";
  for (const auto& r : rules_)
    if (r.id != root_) out += "<" + jsgf_name(r.id) + "> = " + body(r) + ";\n";
  return out;
}

std::optional<std::string> SrgsGrammar::tag_for(const std::vector<std::string>& words) const {
  using Cont = std::function<bool(size_t, const std::string&)>;
  std::function<bool(const SrgsNode&, size_t, const std::string&, int, const Cont&)> match;
  std::function<bool(const SrgsNode&, size_t, size_t, const std::string&, int, const Cont&)> seq;
  std::function<bool(const SrgsNode&, int, size_t, const std::string&, int, const Cont&)> rep;
  constexpr int kMaxDepth = 400;

  seq = [&](const SrgsNode& n, size_t i, size_t pos, const std::string& tag, int depth,
            const Cont& k) -> bool {
    if (i == n.children.size()) return k(pos, tag);
    return match(n.children[i], pos, tag, depth + 1,
                 [&](size_t p, const std::string& t) { return seq(n, i + 1, p, t, depth + 1, k); });
  };
  rep = [&](const SrgsNode& n, int count, size_t pos, const std::string& tag, int depth,
            const Cont& k) -> bool {
    if (depth > kMaxDepth) return false;
    if (n.max_repeat == -1 || count < n.max_repeat) {
      const bool more = seq(n, 0, pos, tag, depth + 1, [&](size_t p, const std::string& t) {
        if (p == pos && count >= n.min_repeat) return false;  // no progress
        return rep(n, count + 1, p, t, depth + 1, k);
      });
      if (more) return true;
    }
    return count >= n.min_repeat && k(pos, tag);
  };
  match = [&](const SrgsNode& n, size_t pos, const std::string& tag, int depth,
              const Cont& k) -> bool {
    if (depth > kMaxDepth) return false;
    switch (n.kind) {
      case Kind::kToken:
        return pos < words.size() && words[pos] == n.text && k(pos + 1, tag);
      case Kind::kTag:
        return k(pos, n.text);
      case Kind::kRuleRef:
        return match(rules_[index_.at(n.text)].body, pos, tag, depth + 1, k);
      case Kind::kOneOf:
        for (const auto& c : n.children)
          if (match(c, pos, tag, depth + 1, k)) return true;
        return false;
      case Kind::kSequence:
        return rep(n, 0, pos, tag, depth + 1, k);
    }
    return false;
  };

  std::optional<std::string> found;
  match(rules_[index_.at(root_)].body, 0, "", 0, [&](size_t p, const std::string& t) {
    if (p != words.size()) return false;
    found = t;
    return true;
  });
  return found;
}

}  // namespace dreamsense::speech
