#include "dreamsense/ui/operator_page.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/export/overlay.hpp"
#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <httplib.h>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

namespace dreamsense::ui {

namespace {

// The page: self-contained (no external resource), polling /api/operator once a second.
// `?test_mark=1` presses the mark button once after the second update (the browser test).
const char* kPage = R"html(
<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>dreamsense: operator</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
*{box-sizing:border-box}
body{font-family:system-ui,sans-serif;margin:0;background:#f2f2f2;color:#222}
#strip{display:flex;flex-wrap:wrap;align-items:center;gap:6px 18px;padding:8px 14px;background:#263238;color:#fff;font-size:17px}
#strip .item{white-space:nowrap}
#clock{font-size:26px;font-variant-numeric:tabular-nums;font-weight:600}
.rec-on{color:#fff;background:#c62828;border-radius:4px;padding:2px 8px;font-weight:600}
.rec-off{color:#cfd8dc}
.bad{color:#fff;background:#e65100;border-radius:4px;padding:2px 8px}
.good{color:#a5d6a7}
#mark{margin-left:auto;font-size:20px;padding:6px 22px;border:0;border-radius:6px;background:#ffca28;color:#222;font-weight:700;cursor:pointer}
#mark:active{background:#ffb300}
#offline-banner{display:none;padding:6px 14px;background:#ffe0b2;color:#6d3000;font-weight:600}
#ind{display:grid;grid-template-columns:1.2fr 1.6fr 1fr;gap:10px;padding:10px 14px}
.card{border-radius:10px;padding:12px 16px;background:#fff;box-shadow:0 1px 3px #0003;min-height:120px}
.card h3{margin:0 0 6px;font-size:14px;text-transform:uppercase;letter-spacing:.05em;opacity:.75}
.big{font-size:30px;font-weight:700;line-height:1.15}
.sub{font-size:18px;margin-top:6px}
#gaze.mutual{background:#2e9d4a;color:#fff}
#gaze.not_mutual{background:#78909c;color:#fff}
#gaze.unknown{background:#e0e0e0;color:#555}
#cams{display:flex;flex-wrap:wrap;gap:10px;padding:0 14px 10px}
.cam{flex:1 1 30%;min-width:260px;background:#000;border:4px solid #546e7a;border-radius:6px;position:relative}
.cam img{display:block;width:100%;min-height:120px}
.cam .label{position:absolute;right:0;bottom:0;background:#000a;color:#fff;padding:2px 8px;font-size:15px}
.cam.selected{border:6px solid #ffca28}
.cam.selected .label{background:#ffca28;color:#000;font-weight:700}
#lower{display:grid;grid-template-columns:1fr 2fr;gap:10px;padding:0 14px 14px}
#marks li{font-variant-numeric:tabular-nums}
table{border-collapse:collapse;font-size:13px;width:100%}
td,th{border-bottom:1px solid #ddd;padding:2px 6px;text-align:left;vertical-align:top}
tr.no_data td,tr.stale td{color:#8a6d00}tr.disabled td{color:#aaa}tr.sensor_offline td,tr.error td{color:#b71c1c}
#error{color:#b71c1c;font-weight:600}
</style></head><body>
<div id="strip">
  <span class="item" id="clock" title="session clock">--:--</span>
  <span class="item" id="rec">recording: ?</span>
  <span class="item" id="drops"></span>
  <span class="item" id="offline"></span>
  <span class="item" id="face-model"></span>
  <span class="item" id="error"></span>
  <button id="mark" title="write a marker into the session (key M)">Mark (M)</button>
</div>
<div id="offline-banner"></div>
<div id="ind">
  <div class="card unknown" id="gaze"><h3>Mutual gaze</h3><div class="big" id="gaze-text">waiting</div><div class="sub" id="gaze-sub"></div></div>
  <div class="card" id="speech"><h3>Last utterance</h3><div class="big" id="speech-text">&mdash;</div><div class="sub" id="speech-sub"></div></div>
  <div class="card" id="gesture"><h3>Gesture</h3><div class="big" id="gesture-text">&mdash;</div><div class="sub" id="gesture-sub"></div></div>
</div>
<div id="cams"></div>
<div id="lower">
  <div class="card"><h3>Markers</h3><div id="mark-status"></div><ol id="marks"></ol></div>
  <div class="card"><details><summary>All primitives (rounded)</summary>
    <table><thead><tr><th>primitive</th><th>status</th><th>confidence</th><th>value</th></tr></thead><tbody id="rows"></tbody></table>
  </details></div>
</div>
<script>
"use strict";
// Everything shown comes from the session (speech, speaker ids): text nodes only, never HTML.
const params=new URLSearchParams(location.search);
const token=params.get('token')||'';
function api(path,extra){let q=token?'token='+encodeURIComponent(token):'';if(extra)q+=(q?'&':'')+extra;return path+(q?'?'+q:'');}
const $=id=>document.getElementById(id);
function text(id,s){$(id).textContent=(s===null||s===undefined)?'':String(s);}
function round(v){
  if(typeof v==='number')return Number.isInteger(v)?v:Math.round(v*100)/100;
  if(Array.isArray(v))return v.map(round);
  if(v&&typeof v==='object'){const o={};for(const[k,x]of Object.entries(v))o[k]=round(x);return o;}
  return v;}
let updates=0,markPending=false,testMarkDone=false;
async function mark(){
  if(markPending)return;markPending=true;text('mark-status','sending marker...');
  try{
    const r=await fetch(api('/api/marker'),{method:'POST',headers:{'Content-Type':'application/json'},body:JSON.stringify({label:'mark'})});
    const j=await r.json().catch(()=>({}));
    if(r.status===201){text('mark-status','marker '+j.n+' written at '+j.clock);$('mark-status').dataset.markerN=j.n;}
    else text('mark-status','marker not written: '+(j.error||r.status));
  }catch(e){text('mark-status','marker not written: '+e);}
  markPending=false;refresh();}
$('mark').addEventListener('click',mark);
document.addEventListener('keydown',e=>{if((e.key==='m'||e.key==='M')&&!e.repeat&&!e.ctrlKey&&!e.altKey&&!e.metaKey){e.preventDefault();mark();}});
function showState(s){
  text('clock',s.clock);
  const rec=$('rec');
  if(s.recording&&s.recording.on){rec.className='item rec-on';rec.textContent='\u25CF REC '+s.recording.size;}
  else{rec.className='item rec-off';rec.textContent='not recording';}
  const d=(s.streams||[]).map(x=>x.id+': '+x.dropped+' dropped');
  const anyDrop=(s.streams||[]).some(x=>x.dropped>0);
  $('drops').className='item '+(anyDrop?'bad':'good');
  text('drops',d.length?'frames not analysed \u2014 '+d.join(', '):'');
  const fm=$('face-model');
  fm.className='item '+(s.face_model&&s.face_model.startsWith('generic')?'bad':'good');
  text('face-model',s.face_model?'head pose / gaze: '+s.face_model:'');
  const off=s.sensors_offline||[];
  $('offline').className='item '+(off.length?'bad':'good');
  text('offline',off.length?'OFFLINE: '+off.join(', '):'all sensors delivering');
  const b=$('offline-banner');b.style.display=off.length?'block':'none';
  b.textContent=off.length?'Sensor offline: '+off.join(', ')+' \u2014 no data for more than 1 s':'';
  const g=s.mutual_gaze||{};
  $('gaze').className='card '+(g.state==='mutual'?'mutual':g.state==='not_mutual'?'not_mutual':'unknown');
  text('gaze-text',g.text||'waiting');
  text('gaze-sub',g.state==='mutual'?'held '+g.held:(g.detail||''));
  const u=s.utterance;
  if(u){text('speech-text','\u201C'+u.text+'\u201D');
    text('speech-sub',[u.speaker?'speaker: '+u.speaker:'speaker: ?',u.direction?'from '+u.direction:null,u.at?'at '+u.at+' ('+u.ago+' ago)':null].filter(x=>x).join(' \u00B7 '));}
  else{text('speech-text','\u2014');text('speech-sub','nothing recognised yet');}
  const ge=s.gesture||{};
  text('gesture-text',ge.text||'\u2014');text('gesture-sub',ge.detail||'');
  const ms=(s.markers||[]).slice().reverse().map(m=>{const li=document.createElement('li');li.value=m.n;li.textContent=m.clock+'  '+m.label;return li;});
  $('marks').replaceChildren(...ms);
  const cams=s.cameras||[];
  const div=$('cams');
  if(div.dataset.ids!==cams.join(',')){div.dataset.ids=cams.join(',');div.replaceChildren();
    for(const c of cams){const f=document.createElement('div');f.className='cam';f.id='cam_'+c;
      const i=document.createElement('img');i.alt=c;const l=document.createElement('span');l.className='label';
      f.appendChild(i);f.appendChild(l);div.appendChild(f);}}
  for(const c of cams){const f=$('cam_'+c);const sel=c===s.selected_camera;f.className='cam'+(sel?' selected':'');
    f.querySelector('.label').textContent=c+(sel?'  \u2605 selected':'')+(s.faces&&s.faces[c]!==undefined?'  \u00B7 '+s.faces[c]+' face'+(s.faces[c]===1?'':'s'):'');
    f.querySelector('img').src=api('/camera/'+c+'.jpg','t='+s.ticks);}}
function showPrimitives(p){
  const rows=[];
  for(const name of (p.order||Object.keys(p.primitives))){const r=p.primitives[name];if(!r)continue;
    const v=r.value===null||r.value===undefined?'':JSON.stringify(round(r.value));
    const tr=document.createElement('tr');tr.className=String(r.status);
    for(const c of [r.id+' '+name,String(r.status),r.confidence===null||r.confidence===undefined?'':Number(r.confidence).toFixed(2),v.length>200?v.slice(0,200)+'\u2026':v]){
      const td=document.createElement('td');td.textContent=c;tr.appendChild(td);}
    rows.push(tr);}
  $('rows').replaceChildren(...rows);}
async function refresh(){
  try{
    const s=await (await fetch(api('/api/operator'))).json();
    showState(s);
    if($('rows').closest('details').open)showPrimitives(await (await fetch(api('/api/primitives'))).json());
    text('error','');updates++;document.body.dataset.updates=updates;
    if(params.get('test_mark')==='1'&&!testMarkDone&&updates>=2){testMarkDone=true;$('mark').click();}
  }catch(e){text('error','not running');}}
setInterval(refresh,1000);refresh();
</script></body></html>
)html";

// Worker threads of the page's server (each open connection holds one while it is read).
constexpr size_t kWorkerThreads = 32;
constexpr size_t kMarkersShown = 8;

bool is_loopback(const std::string& host) {
  return host == "127.0.0.1" || host == "localhost" || host == "::1";
}

// The Host header's name (without port).
std::string host_name(const std::string& host_header) {
  std::string name = host_header;
  if (!name.empty() && name.front() == '[') {  // [::1]:port
    const auto close = name.find(']');
    return close == std::string::npos ? name : name.substr(1, close - 1);
  }
  if (const auto colon = name.rfind(':'); colon != std::string::npos) name = name.substr(0, colon);
  return name;
}

// The Host header's name is one this page is served as.
bool host_allowed(const std::string& host_header, const std::string& configured) {
  const std::string name = host_name(host_header);
  return is_loopback(name) || name == configured;
}

std::string random_token() {
  std::random_device rd;
  std::string t;
  for (int i = 0; i < 4; ++i) t += fmt::format("{:08x}", rd());
  return t;
}

// Compares without stopping at the first difference (the token's length is not secret).
bool same_secret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char d = 0;
  for (size_t i = 0; i < a.size(); ++i) d |= static_cast<unsigned char>(a[i] ^ b[i]);
  return d == 0;
}

double round_to(double v, int decimals) {
  const double f = std::pow(10.0, decimals);
  return std::round(v * f) / f;
}

}  // namespace

// "01:23.4" (minutes:seconds.tenths of the session clock), "1:02:03.4" from an hour on.
std::string session_clock_text(int64_t ns) {
  const int64_t tenths = std::max<int64_t>(ns, 0) / 100'000'000;
  const int64_t s = tenths / 10, h = s / 3600, m = (s / 60) % 60;
  if (h > 0) return fmt::format("{}:{:02}:{:02}.{}", h, m, s % 60, tenths % 10);
  return fmt::format("{:02}:{:02}.{}", m, s % 60, tenths % 10);
}

// "0 B", "830 kB", "12.3 MB", "1.23 GB" (decimal units).
std::string byte_size_text(uint64_t bytes) {
  const double b = static_cast<double>(bytes);
  if (b < 1e3) return fmt::format("{} B", bytes);
  if (b < 1e6) return fmt::format("{:.0f} kB", b / 1e3);
  if (b < 1e9) return fmt::format("{:.1f} MB", b / 1e6);
  return fmt::format("{:.2f} GB", b / 1e9);
}

namespace {

const nlohmann::json* value_of(const std::map<std::string, nlohmann::json>& m,
                               const std::string& name) {
  auto it = m.find(name);
  if (it == m.end() || !it->second.contains("value") || !it->second["value"].is_object())
    return nullptr;
  return &it->second["value"];
}

std::string status_of(const std::map<std::string, nlohmann::json>& m, const std::string& name) {
  auto it = m.find(name);
  return it == m.end() ? std::string() : it->second.value("status", std::string());
}

}  // namespace

Status OperatorPageOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (host.empty()) add("host is empty");
  if (port < 0 || port > 65535) add(fmt::format("port must be in [0, 65535] (is {})", port));
  if (jpeg_quality < 1 || jpeg_quality > 100)
    add(fmt::format("jpeg_quality must be in [1, 100] (is {})", jpeg_quality));
  if (max_image_width < 16)
    add(fmt::format("max_image_width must be >= 16 (is {})", max_image_width));
  for (char c : token)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') {
      add("token may hold letters, digits, '-' and '_' only");
      break;
    }
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "OperatorPageOptions: {}", bad);
  return ok_status();
}

struct OperatorPage::Impl {
  OperatorPageOptions options;
  httplib::Server server;
  std::thread thread;
  int port = 0;
  mutable std::mutex mutex;
  int64_t stamp_ns = 0;
  std::map<std::string, nlohmann::json> records;  // by primitive name, catalogue order below
  std::map<std::string, nlohmann::json> last_ok;  // each primitive's latest ok record
  std::map<SensorId, FramePtr> frames;
  // Per camera the latest tick that held its frame, with the blackboard after that tick
  // (update_view): its picture is drawn with the overlay.
  struct Viewed {
    std::shared_ptr<const MultiFrame> tick;
    BlackboardView view;
  };
  std::map<SensorId, Viewed> viewed;
  std::map<SensorId, CameraModel> camera_models;  // head axes and gaze rays
  // The selected camera of the latest viewed tick (keys::kSelectedCamera, as the pictures draw
  // it); before any update_view, getFaces' selected_camera.
  std::optional<std::optional<SensorId>> view_selected;
  std::map<SensorId, std::pair<uint64_t, std::string>> jpeg_cache;  // camera -> (tick, jpeg)
  // The latest getFaces answer's boxes per camera (full-resolution pixels), for blur_faces.
  std::map<SensorId, std::vector<cv::Rect2d>> face_boxes;
  nlohmann::json status = nlohmann::json::object();
  MarkerHandler marker_handler;
  std::vector<nlohmann::json> markers;  // as shown: {n, clock, label}
  size_t marker_count = 0;

  ~Impl() {
    server.stop();
    if (thread.joinable()) thread.join();
  }

  nlohmann::json primitives_json() const {
    std::lock_guard lock(mutex);
    nlohmann::json out = {{"stamp_ns", stamp_ns},
                          {"primitives", nlohmann::json::object()},
                          {"order", nlohmann::json::array()}};
    for (const auto& i : primitives::catalogue())
      if (auto it = records.find(i.name); it != records.end()) {
        out["primitives"][i.name] = it->second;
        out["order"].push_back(i.name);
      }
    return out;
  }

  nlohmann::json state_json() const;

  bool camera_jpeg(const std::string& id, std::string& jpeg) {
    FramePtr f;
    std::vector<cv::Rect2d> boxes;
    std::shared_ptr<const MultiFrame> t;
    std::optional<BlackboardView> v;
    {
      std::lock_guard lock(mutex);
      auto it = frames.find(id);
      if (it == frames.end()) return false;
      f = it->second;
      if (auto w = viewed.find(id); w != viewed.end() && w->second.tick->frame(id) == f) {
        t = w->second.tick;
        v = w->second.view;
        if (auto c = jpeg_cache.find(id); c != jpeg_cache.end() && c->second.first == t->tick) {
          jpeg = c->second.second;
          return true;
        }
      }
      if (auto b = face_boxes.find(id); b != face_boxes.end()) boxes = b->second;
    }
    const auto* c = std::get_if<ColorImage>(&f->payload);
    if (c == nullptr || c->image.empty()) return false;
    cv::Mat img;
    const int w = std::min(c->image.cols, options.max_image_width);
    const int h = std::max(2, c->image.rows * w / std::max(1, c->image.cols));
    if (t) {  // boxes, landmarks, gaze and the selected face, drawn from the blackboard
      exporters::OverlayOptions oo;
      oo.camera = id;
      {
        std::lock_guard lock(mutex);
        oo.cameras = camera_models;
      }
      oo.blur_faces = options.blur_faces;
      img = exporters::draw_overlay(c->image, id, *t, *v, oo, {w, h});
    } else {
      img = c->image;
      if (options.blur_faces && !boxes.empty()) {
        std::vector<cv::Rect> regions;
        for (const cv::Rect2d& b : boxes)
          regions.emplace_back(cv::Rect2d(b.x - 0.25 * b.width, b.y - 0.25 * b.height,
                                          1.5 * b.width, 1.5 * b.height));
        img = img.clone();
        exporters::blur_regions(img, regions);
      }
      if (img.cols > w) cv::resize(img, img, {w, h}, 0, 0, cv::INTER_AREA);
    }
    std::vector<uchar> buf;
    cv::imencode(".jpg", img, buf, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality});
    jpeg.assign(buf.begin(), buf.end());
    if (t) {
      std::lock_guard lock(mutex);
      jpeg_cache[id] = {t->tick, jpeg};
    }
    return true;
  }
};

nlohmann::json OperatorPage::Impl::state_json() const {
  using nlohmann::json;
  std::lock_guard lock(mutex);
  json s = json::object();
  const int64_t now = std::max(stamp_ns, status.value("stamp_ns", int64_t{0}));
  s["stamp_ns"] = now;
  s["clock_s"] = round_to(static_cast<double>(now) * 1e-9, 1);
  s["clock"] = session_clock_text(now);
  s["ticks"] = status.value("ticks", 0);

  const json rec = status.value("recording", json::object());
  const uint64_t bytes = rec.value("bytes", uint64_t{0});
  s["recording"] = {
      {"on", rec.value("on", false)}, {"bytes", bytes}, {"size", byte_size_text(bytes)}};

  json streams = json::array();
  json offline = json::array();
  const json stream_status = status.value("streams", json::object());
  for (const auto& [id, st] : stream_status.items()) {
    streams.push_back({{"id", id},
                       {"dropped", st.value("dropped", uint64_t{0})},
                       {"offline", st.value("offline", false)}});
    if (st.value("offline", false)) offline.push_back(id);
  }
  s["streams"] = streams;
  s["sensors_offline"] = offline;
  // A live self-calibration's state (absent: the session's own calibration or none was asked).
  s["face_model"] = status.contains("face_model") ? status["face_model"] : json();

  json cams = json::array();
  for (const auto& [id, f] : frames) cams.push_back(id);
  s["cameras"] = cams;
  s["selected_camera"] = nullptr;
  s["faces"] = json::object();
  if (view_selected && *view_selected) s["selected_camera"] = **view_selected;
  if (const json* v = value_of(records, "getFaces"); v && status_of(records, "getFaces") == "ok") {
    if (!view_selected && v->contains("selected_camera") && (*v)["selected_camera"].is_string())
      s["selected_camera"] = (*v)["selected_camera"];
    const json per_camera = v->value("cameras", json::object());
    for (const auto& [cam, list] : per_camera.items())
      s["faces"][cam] = list.is_array() ? list.size() : 0;
  }

  // Mutual gaze: the hold rule's state and how long it has held.
  json g = {{"state", "waiting"}, {"text", "waiting for the analysis"}};
  const std::string gs = status_of(records, "checkMutualGaze");
  if (const json* v = value_of(records, "checkMutualGaze"); v && gs == "ok") {
    const bool mutual = v->value("mutual", false);
    const std::string target = v->value("target", std::string("robot"));
    const double held = round_to(v->value("held_s", 0.0), 1);
    g = {{"state", mutual ? "mutual" : "not_mutual"},
         {"held_s", held},
         {"held", fmt::format("{:.1f} s", held)},
         {"target", target},
         {"text", mutual ? "Looking at the " + target : "Not looking at the " + target}};
  } else if (!gs.empty()) {
    g = {{"state", gs},
         {"text", gs == "disabled" ? "not analysed" : "no gaze estimate"},
         {"detail", gs == "no_data"          ? "no face, or the eyes are not visible"
                    : gs == "stale"          ? "the last estimate is too old"
                    : gs == "sensor_offline" ? "camera offline"
                                             : gs}};
  }
  s["mutual_gaze"] = g;

  // The last utterance: text, who spoke it and from where.
  s["utterance"] = nullptr;
  if (const json* v = value_of(last_ok, "recognizeSpeech")) {
    const int64_t end = v->value("end_ns", now);
    const double ago = round_to(static_cast<double>(now - end) * 1e-9, 0);
    json u = {{"text", v->value("text", std::string())},
              {"confidence", round_to(v->value("confidence", 0.0), 2)},
              {"at", session_clock_text(end)},
              {"ago_s", std::max(0.0, ago)},
              {"ago", fmt::format("{:.0f} s", std::max(0.0, ago))},
              {"speaker", nullptr},
              {"direction", nullptr}};
    if (const json* sp = value_of(last_ok, "identifyVoice")) {
      const std::string name = sp->value("name", std::string());
      u["speaker"] = name.empty() ? sp->value("speaker_id", std::string("?")) : name;
    }
    if (const json* d = value_of(last_ok, "getSoundDirection")) {
      const double az = round_to(d->value("azimuth_deg", 0.0), 0);
      u["azimuth_deg"] = az;
      u["direction"] = fmt::format("{:.0f}\u00b0 azimuth", az);
    }
    s["utterance"] = u;
  }

  // The current gesture (identifyTrajectory's label).
  const std::string ts = status_of(records, "identifyTrajectory");
  json ge = {{"state", ts.empty() ? "waiting" : ts}, {"text", "\u2014"}};
  if (const json* v = value_of(records, "identifyTrajectory"); v && ts == "ok") {
    const std::string label = v->value("label", std::string("none"));
    ge["label"] = label;
    ge["text"] = label == "none" ? "no gesture" : label;
    double best = 0;
    const json scores = v->value("scores", json::object());
    for (const auto& [k, sc] : scores.items())
      if (k == label && sc.is_number()) best = sc.get<double>();
    if (best > 0) ge["detail"] = fmt::format("score {:.2f}", best);
  } else if (!ts.empty()) {
    ge["detail"] = ts == "disabled" ? "not analysed" : "no skeleton (" + ts + ")";
  }
  s["gesture"] = ge;

  s["markers"] = markers;
  s["marker_count"] = marker_count;
  return s;
}

OperatorPage::OperatorPage(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OperatorPage::~OperatorPage() = default;

Result<std::unique_ptr<OperatorPage>> OperatorPage::start(const OperatorPageOptions& options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  auto m = std::make_unique<Impl>();
  m->options = options;
  if (m->options.token.empty() && !is_loopback(options.host)) m->options.token = random_token();
  Impl* raw = m.get();
  m->server.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(kPage, "text/html; charset=utf-8");
  });
  m->server.Get("/api/primitives", [raw](const httplib::Request&, httplib::Response& res) {
    res.set_content(raw->primitives_json().dump(), "application/json");
  });
  m->server.Get("/api/operator", [raw](const httplib::Request&, httplib::Response& res) {
    res.set_content(raw->state_json().dump(), "application/json");
  });
  m->server.Get("/api/status", [raw](const httplib::Request&, httplib::Response& res) {
    std::lock_guard lock(raw->mutex);
    res.set_content(raw->status.dump(), "application/json");
  });
  m->server.Get("/api/cameras", [raw](const httplib::Request&, httplib::Response& res) {
    nlohmann::json ids = nlohmann::json::array();
    {
      std::lock_guard lock(raw->mutex);
      for (const auto& [id, f] : raw->frames) ids.push_back(id);
    }
    res.set_content(ids.dump(), "application/json");
  });
  m->server.Get(R"(/camera/([A-Za-z0-9_.\-]+)\.jpg)",
                [raw](const httplib::Request& req, httplib::Response& res) {
                  std::string jpeg;
                  if (!raw->camera_jpeg(req.matches[1], jpeg)) {
                    res.status = 404;
                    res.set_content("no such camera", "text/plain");
                    return;
                  }
                  res.set_header("Cache-Control", "no-store");
                  res.set_content(jpeg, "image/jpeg");
                });
  m->server.Post("/api/marker", [raw](const httplib::Request& req, httplib::Response& res) {
    auto answer = [&res](int code, const nlohmann::json& j) {
      res.status = code;
      res.set_content(j.dump(), "application/json");
    };
    // application/json cannot be sent cross-site without a CORS preflight, which is never
    // answered: another web page cannot make markers.
    if (req.get_header_value("Content-Type").rfind("application/json", 0) != 0)
      return answer(415, {{"error", "Content-Type must be application/json"}});
    const auto body = nlohmann::json::parse(req.body, nullptr, false);
    std::string label = "mark";
    if (!body.is_discarded() && body.is_object() && body.contains("label") &&
        body["label"].is_string())
      label = body["label"].get<std::string>();
    std::string clean;
    for (char c : label)
      if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f && clean.size() < 80) clean += c;
    if (clean.empty()) clean = "mark";
    MarkerHandler handler;
    {
      std::lock_guard lock(raw->mutex);
      handler = raw->marker_handler;
    }
    if (!handler) return answer(503, {{"error", "markers are not recorded in this run"}});
    auto made = handler(clean);
    if (!made) return answer(500, {{"error", made.error().message}});
    nlohmann::json j = *made;
    const int64_t stamp = j.value("stamp_ns", int64_t{0});
    j["clock"] = session_clock_text(stamp);
    {
      std::lock_guard lock(raw->mutex);
      ++raw->marker_count;
      raw->markers.push_back({{"n", j.value("n", static_cast<int>(raw->marker_count))},
                              {"clock", j["clock"]},
                              {"label", j.value("label", clean)},
                              {"stamp_ns", stamp}});
      if (raw->markers.size() > kMarkersShown) raw->markers.erase(raw->markers.begin());
    }
    log::info("operator marker {} at {} ({})", j.value("n", 0), j["clock"].get<std::string>(),
              j.value("label", clean));
    answer(201, j);
  });
  // Requests whose Host is not this page's own name are refused: a web page elsewhere could
  // otherwise reach 127.0.0.1 through DNS rebinding. A POST from another origin is refused too,
  // and off loopback every request needs the token.
  m->server.set_pre_routing_handler([raw](const httplib::Request& req, httplib::Response& res) {
    auto refuse = [&res](int code, const char* why) {
      res.status = code;
      res.set_content(why, "text/plain");
      return httplib::Server::HandlerResponse::Handled;
    };
    const std::string host = req.get_header_value("Host");
    if (!host_allowed(host, raw->options.host))
      return refuse(403, "forbidden: unexpected Host header");
    if (req.method == "POST" && req.has_header("Origin") &&
        req.get_header_value("Origin") != "http://" + host)
      return refuse(403, "forbidden: the request comes from another web page");
    const std::string& token = raw->options.token;
    if (!token.empty()) {
      const std::string given = req.has_param("token") ? req.get_param_value("token")
                                                       : req.get_header_value("X-Dreamsense-Token");
      if (!same_secret(given, token))
        return refuse(401, "unauthorised: add ?token=<the token live printed>");
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  // Slow or idle clients cannot starve the page: a connection that sends nothing for 2 s is
  // closed, and the worker pool is much larger than a handful of such connections.
  m->server.set_read_timeout(2, 0);
  m->server.set_write_timeout(2, 0);
  m->server.set_keep_alive_timeout(2);
  m->server.set_keep_alive_max_count(20);
  m->server.new_task_queue = [] { return new httplib::ThreadPool(kWorkerThreads); };
  // SO_REUSEADDR only: cpp-httplib's default SO_REUSEPORT would let a second page bind the same
  // port and silently share its requests.
  m->server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  if (options.port == 0) {
    m->port = m->server.bind_to_any_port(options.host);
    if (m->port <= 0)
      return make_error(ErrorCode::kIoError, "operator page: cannot listen on {}", options.host);
  } else {
    if (!m->server.bind_to_port(options.host, options.port))
      return make_error(ErrorCode::kIoError,
                        "operator page: cannot listen on {}:{} (port in use, or not this "
                        "machine's address)",
                        options.host, options.port);
    m->port = options.port;
  }
  m->thread = std::thread([raw] { raw->server.listen_after_bind(); });
  // stop() is a no-op until the server runs: wait for it, so destruction never hangs.
  for (int i = 0; i < 2000 && !m->server.is_running(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  if (!m->server.is_running())
    return make_error(ErrorCode::kIoError, "operator page: the server did not start on {}:{}",
                      options.host, m->port);
  if (!is_loopback(options.host))
    log::warn(
        "operator page on {}: other machines can see the session's cameras; every request "
        "needs the access token (in the page's URL)",
        options.host);
  return std::unique_ptr<OperatorPage>(new OperatorPage(std::move(m)));
}

void OperatorPage::update(const std::vector<primitives::PrimitiveRecord>& records) {
  std::lock_guard lock(impl_->mutex);
  for (const auto& r : records) {
    if (r.id == primitives::PrimitiveId::kGetFaces) {  // the faces to blur (none: none found)
      impl_->face_boxes.clear();
      if (const auto* v = r.value_as<primitives::FacesValue>(); v != nullptr && r.ok())
        for (const auto& [cam, list] : v->cameras)
          for (const auto& d : list) impl_->face_boxes[cam].push_back(d.box_px);
    }
    const std::string name = primitives::info(r.id).name;
    nlohmann::json j = exporters::to_json(r);
    if (r.ok()) impl_->last_ok[name] = j;
    impl_->records[name] = std::move(j);
    impl_->stamp_ns = std::max(impl_->stamp_ns, r.stamp.ns());
  }
}

void OperatorPage::update_frame(const SensorId& camera, FramePtr frame) {
  if (!frame || !std::holds_alternative<ColorImage>(frame->payload)) return;
  std::lock_guard lock(impl_->mutex);
  impl_->frames[camera] = std::move(frame);
}

void OperatorPage::update_view(const MultiFrame& tick, const BlackboardView& view) {
  auto t = std::make_shared<MultiFrame>();
  t->stamp = tick.stamp;
  t->tick = tick.tick;
  for (const auto& [id, f] : tick.frames)
    if (f && std::holds_alternative<ColorImage>(f->payload)) t->frames[id] = f;
  std::optional<SensorId> selected;
  if (auto e = view.get(keys::kSelectedCamera); e && e->present() && e->stamp == tick.stamp)
    selected = e->value->camera;
  std::lock_guard lock(impl_->mutex);
  impl_->view_selected = selected;
  for (const auto& [id, f] : t->frames) {
    impl_->frames[id] = f;
    impl_->viewed[id] = {t, view};
  }
}

void OperatorPage::set_camera_models(std::map<SensorId, CameraModel> models) {
  std::lock_guard lock(impl_->mutex);
  impl_->camera_models = std::move(models);
}

void OperatorPage::set_status(nlohmann::json status) {
  std::lock_guard lock(impl_->mutex);
  impl_->status = std::move(status);
}

void OperatorPage::set_marker_handler(MarkerHandler handler) {
  std::lock_guard lock(impl_->mutex);
  impl_->marker_handler = std::move(handler);
}

nlohmann::json OperatorPage::operator_state_json() const { return impl_->state_json(); }

int OperatorPage::port() const { return impl_->port; }
const std::string& OperatorPage::token() const { return impl_->options.token; }
std::string OperatorPage::url() const {
  const std::string& h = impl_->options.host;
  const std::string host = h.find(':') != std::string::npos ? "[" + h + "]" : h;
  return fmt::format("http://{}:{}/{}", host, impl_->port,
                     impl_->options.token.empty() ? "" : "?token=" + impl_->options.token);
}

}  // namespace dreamsense::ui
