#include "dreamsense/ui/operator_page.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/export/overlay.hpp"
#include "dreamsense/export/primitive_json.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <httplib.h>
#include <map>
#include <mutex>
#include <thread>

namespace dreamsense::ui {

namespace {

const char* kPage = R"html(<!doctype html>
<html><head><meta charset="utf-8"><title>dreamsense live</title>
<style>
body{font-family:sans-serif;margin:1em;background:#fafafa}
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}
.ok{background:#e6f4e6}.no_data{background:#fff8e0}.disabled{color:#999}.error{background:#fde0e0}
.cams img{max-width:32%;margin-right:4px;border:1px solid #888}
code{white-space:pre-wrap;word-break:break-all}
</style></head><body>
<h2>dreamsense live <small id="status"></small></h2>
<div class="cams" id="cams"></div>
<table><thead><tr><th>primitive</th><th>status</th><th>confidence</th><th>value</th></tr></thead>
<tbody id="rows"></tbody></table>
<script>
async function refresh(){
  try{
    const p=await (await fetch('/api/primitives')).json();
    const s=await (await fetch('/api/status')).json();
    document.getElementById('status').textContent=JSON.stringify(s);
    // Values come from the session (e.g. speaker folder names): text nodes only, never HTML.
    const rows=[];
    for(const [name,r] of Object.entries(p.primitives)){
      const v=r.value===null?'':JSON.stringify(r.value);
      const tr=document.createElement('tr');tr.className=String(r.status);
      const cells=[r.id+' '+name,String(r.status),r.confidence===null?'':Number(r.confidence).toFixed(2),null];
      for(const c of cells){const td=document.createElement('td');
        if(c===null){const code=document.createElement('code');code.textContent=v.length>300?v.slice(0,300)+'...':v;td.appendChild(code);}
        else td.textContent=c;
        tr.appendChild(td);}
      rows.push(tr);
    }
    document.getElementById('rows').replaceChildren(...rows);
    const cams=await (await fetch('/api/cameras')).json();
    const div=document.getElementById('cams');
    if(div.childElementCount!==cams.length){div.replaceChildren();for(const c of cams){const i=document.createElement('img');i.id='cam_'+c;i.title=c;div.appendChild(i);}}
    for(const c of cams){document.getElementById('cam_'+c).src='/camera/'+c+'.jpg?t='+Date.now();}
  }catch(e){document.getElementById('status').textContent='(not running)';}
}
setInterval(refresh,1000);refresh();
</script></body></html>
)html";

// Worker threads of the page's server (each open connection holds one while it is read).
constexpr size_t kWorkerThreads = 32;

// The Host header's name (without port) is one this page is served as.
bool host_allowed(const std::string& host_header, const std::string& configured) {
  std::string name = host_header;
  if (!name.empty() && name.front() == '[') {  // [::1]:port
    const auto close = name.find(']');
    name = close == std::string::npos ? name : name.substr(1, close - 1);
  } else if (const auto colon = name.rfind(':'); colon != std::string::npos) {
    name = name.substr(0, colon);
  }
  return name == "127.0.0.1" || name == "localhost" || name == "::1" || name == configured;
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
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "OperatorPageOptions: {}", bad);
  return ok_status();
}

struct OperatorPage::Impl {
  OperatorPageOptions options;
  httplib::Server server;
  std::thread thread;
  int port = 0;
  std::mutex mutex;
  int64_t stamp_ns = 0;
  std::map<std::string, nlohmann::json> records;  // by primitive name, catalogue order below
  std::map<SensorId, FramePtr> frames;
  // The latest getFaces answer's boxes per camera (full-resolution pixels), for blur_faces.
  std::map<SensorId, std::vector<cv::Rect2d>> face_boxes;
  nlohmann::json status = nlohmann::json::object();

  ~Impl() {
    server.stop();
    if (thread.joinable()) thread.join();
  }

  nlohmann::json primitives_json() {
    std::lock_guard lock(mutex);
    nlohmann::json out = {{"stamp_ns", stamp_ns}, {"primitives", nlohmann::json::object()}};
    for (const auto& i : primitives::catalogue())
      if (auto it = records.find(i.name); it != records.end())
        out["primitives"][i.name] = it->second;
    return out;
  }

  bool camera_jpeg(const std::string& id, std::string& jpeg) {
    FramePtr f;
    std::vector<cv::Rect2d> boxes;
    {
      std::lock_guard lock(mutex);
      auto it = frames.find(id);
      if (it == frames.end()) return false;
      f = it->second;
      if (auto b = face_boxes.find(id); b != face_boxes.end()) boxes = b->second;
    }
    const auto* c = std::get_if<ColorImage>(&f->payload);
    if (c == nullptr || c->image.empty()) return false;
    cv::Mat img = c->image;
    if (options.blur_faces && !boxes.empty()) {
      std::vector<cv::Rect> regions;
      for (const cv::Rect2d& b : boxes)
        regions.emplace_back(
            cv::Rect2d(b.x - 0.25 * b.width, b.y - 0.25 * b.height, 1.5 * b.width, 1.5 * b.height));
      img = img.clone();
      exporters::blur_regions(img, regions);
    }
    if (img.cols > options.max_image_width) {
      const double s = static_cast<double>(options.max_image_width) / img.cols;
      cv::resize(img, img, cv::Size(), s, s, cv::INTER_AREA);
    }
    std::vector<uchar> buf;
    cv::imencode(".jpg", img, buf, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality});
    jpeg.assign(buf.begin(), buf.end());
    return true;
  }
};

OperatorPage::OperatorPage(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OperatorPage::~OperatorPage() = default;

Result<std::unique_ptr<OperatorPage>> OperatorPage::start(const OperatorPageOptions& options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  auto m = std::make_unique<Impl>();
  m->options = options;
  Impl* raw = m.get();
  m->server.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(kPage, "text/html; charset=utf-8");
  });
  m->server.Get("/api/primitives", [raw](const httplib::Request&, httplib::Response& res) {
    res.set_content(raw->primitives_json().dump(), "application/json");
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
                  res.set_content(jpeg, "image/jpeg");
                });
  // Requests whose Host is not this page's own name are refused: a web page elsewhere could
  // otherwise reach 127.0.0.1 through DNS rebinding.
  m->server.set_pre_routing_handler([raw](const httplib::Request& req, httplib::Response& res) {
    if (host_allowed(req.get_header_value("Host"), raw->options.host))
      return httplib::Server::HandlerResponse::Unhandled;
    res.status = 403;
    res.set_content("forbidden: unexpected Host header", "text/plain");
    return httplib::Server::HandlerResponse::Handled;
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
  if (options.host != "127.0.0.1" && options.host != "localhost" && options.host != "::1")
    log::warn("operator page on {}: other machines can see the session's cameras", options.host);
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
    impl_->records[primitives::info(r.id).name] = exporters::to_json(r);
    impl_->stamp_ns = std::max(impl_->stamp_ns, r.stamp.ns());
  }
}

void OperatorPage::update_frame(const SensorId& camera, FramePtr frame) {
  if (!frame || !std::holds_alternative<ColorImage>(frame->payload)) return;
  std::lock_guard lock(impl_->mutex);
  impl_->frames[camera] = std::move(frame);
}

void OperatorPage::set_status(nlohmann::json status) {
  std::lock_guard lock(impl_->mutex);
  impl_->status = std::move(status);
}

int OperatorPage::port() const { return impl_->port; }
std::string OperatorPage::url() const {
  return fmt::format("http://{}:{}/", impl_->options.host, impl_->port);
}

}  // namespace dreamsense::ui
