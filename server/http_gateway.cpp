// SPDX-License-Identifier: GPL-3.0-or-later
#include "http_gateway.h"

#include <google/protobuf/util/json_util.h>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <list>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "auth.h"
#include "gridshell/application/files.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::server {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace ssl = net::ssl;
namespace fs = std::filesystem;
using tcp = net::ip::tcp;
using JobFunction = decltype(JobRequest::run);
using Clock = std::chrono::steady_clock;

constexpr auto kIdleTimeout = std::chrono::seconds(60);  // between requests on a connection
constexpr std::size_t kMaxStaticFile = 1u << 30;
constexpr std::size_t kWriteChunk = 256u << 10;  // bytes per write, and per static file read

/// One POST /v1/NAME route: the RPC table entry behind it.
struct Route {
  std::string name;
  bool implemented = false;
  std::string unimplemented;
  bool light = false;  ///< the queue's light lane (Examples)
  std::function<JobFunction(std::shared_ptr<const std::string>)> job;
};

template <class M>
Route route(const M& method) {
  return {method.name, static_cast<bool>(method.run), method.unimplemented, method.light,
          [&method](std::shared_ptr<const std::string> body) -> JobFunction {
            return job_function_from_json(method, std::move(body));
          }};
}

std::string_view view(beast::string_view text) { return {text.data(), text.size()}; }

// Every response: the page and its scripts come only from this gateway, no inline script or
// style, no plugins, no framing; the API's JSON is never sniffed as something else.
constexpr const char* kSecurityHeaders =
    "Content-Security-Policy: default-src 'self'; script-src 'self'; style-src 'self'; "
    "img-src 'self' data: blob:; connect-src 'self'; worker-src 'self' blob:; object-src 'none'; "
    "base-uri 'none'; form-action 'none'; frame-ancestors 'none'\r\n"
    "X-Content-Type-Options: nosniff\r\nReferrer-Policy: no-referrer\r\n";

std::string error_json(const Status& status) {
  nlohmann::json body;
  body["error"] = {{"code", static_cast<int>(status.code)},
                   {"status", code_name(status.code)},
                   {"field", status.field},
                   {"message", status.message}};
  if (!status.suggestions.empty()) {
    nlohmann::json list = nlohmann::json::array();
    google::protobuf::util::JsonPrintOptions options;
    options.preserve_proto_field_names = true;
    for (const v1::Suggestion& s : status.suggestions) {
      std::string text;
      if (google::protobuf::util::MessageToJsonString(s, &text, options).ok())
        list.push_back(nlohmann::json::parse(text));
    }
    body["error"]["suggestions"] = std::move(list);
  }
  return body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

const char* content_type(const fs::path& file) {
  static const std::map<std::string, const char*> kTypes = {{".html", "text/html; charset=utf-8"},
                                                            {".htm", "text/html; charset=utf-8"},
                                                            {".js", "text/javascript"},
                                                            {".mjs", "text/javascript"},
                                                            {".css", "text/css"},
                                                            {".json", "application/json"},
                                                            {".svg", "image/svg+xml"},
                                                            {".png", "image/png"},
                                                            {".jpg", "image/jpeg"},
                                                            {".ico", "image/x-icon"},
                                                            {".wasm", "application/wasm"},
                                                            {".txt", "text/plain; charset=utf-8"},
                                                            {".obj", "text/plain; charset=utf-8"},
                                                            {".map", "application/json"}};
  const auto it = kTypes.find(lower(file.extension().string()));
  return it == kTypes.end() ? "application/octet-stream" : it->second;
}

/// "%2F" -> "/", false for malformed escapes or a NUL.
bool percent_decode(std::string_view in, std::string& out) {
  out.clear();
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out += in[i];
      continue;
    }
    if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(in[i + 2])))
      return false;
    out += static_cast<char>(std::stoi(std::string(in.substr(i + 1, 2)), nullptr, 16));
    i += 2;
  }
  return out.find('\0') == std::string::npos;
}

std::pair<std::string, std::string> split_host_port(const std::string& address) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos || colon + 1 == address.size())
    throw InvalidInput("--http", "expected HOST:PORT, got '" + address + "'");
  std::string host = address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return {host, address.substr(colon + 1)};
}

}  // namespace

struct HttpGateway::Impl {
  HttpOptions options;
  JobQueue& queue;
  std::function<bool()> serving;
  std::map<std::string, Route> routes;
  fs::path static_root;  // canonical, empty = none

  net::io_context io{1};
  tcp::acceptor acceptor{io};
  net::steady_timer accept_backoff{io};
  std::optional<ssl::context> tls;
  std::thread thread;
  int port = 0;
  bool stopping = false;  // I/O thread only

  /// What a connection is doing, for the budgets: the first four wait for a client and may be
  /// told to give way (evicted) when a new connection or body needs room.
  enum class Phase { Handshake, Idle, Header, Body, Busy, Closing };

  struct SessionBase {
    virtual ~SessionBase() = default;
    virtual void stop() = 0;   // I/O thread
    virtual void evict() = 0;  // I/O thread: close now, release the body reserved
    std::string address;       // the client's IP address
    Phase phase = Phase::Handshake;
    Clock::time_point last_activity = Clock::now();
    std::size_t reserved = 0;  // bytes of the body budget held
    bool waiting() const { return phase <= Phase::Body; }
  };
  std::list<std::weak_ptr<SessionBase>> sessions;  // I/O thread only
  std::size_t body_in_use = 0;                     // I/O thread only
  std::uint64_t evicted = 0;                       // connections told to give way

  std::mutex exit_mutex;
  std::condition_variable exited_cv;
  bool exited = false;
  bool stopped = false;

  Impl(HttpOptions o, JobQueue& q, const Methods& methods, std::function<bool()> s)
      : options(std::move(o)), queue(q), serving(std::move(s)) {
    routes["/v1/patch"] = route(methods.patch);
    routes["/v1/design"] = route(methods.design);
    routes["/v1/simulate"] = route(methods.simulate);
    routes["/v1/run"] = route(methods.run);
    routes["/v1/geodesic"] = route(methods.geodesic);
    routes["/v1/load"] = route(methods.load);
    routes["/v1/examples"] = route(methods.examples);
    routes["/v1/fabricate"] = route(methods.fabricate);
    routes["/v1/options"] = route(methods.options);
    routes["/v1/layout"] = route(methods.layout);
    routes["/v1/runlayout"] = route(methods.run_layout);
  }

  template <class Stream>
  class Session;

  void accept();

  /// The live sessions (expired entries dropped).
  std::vector<std::shared_ptr<SessionBase>> live() {
    std::vector<std::shared_ptr<SessionBase>> all;
    for (auto it = sessions.begin(); it != sessions.end();)
      if (auto session = it->lock()) {
        all.push_back(std::move(session));
        ++it;
      } else {
        it = sessions.erase(it);
      }
    return all;
  }

  /// Room for a new connection from `address`: the least recently active waiting connection
  /// of that address gives way when it has its share, else one of the address with the most
  /// connections when all are taken. False when nobody can give way.
  bool admit(const std::string& address) {
    auto all = live();
    std::map<std::string, std::size_t> count;
    for (const auto& s : all)
      if (s->phase != Phase::Closing) ++count[s->address];
    std::size_t total = 0;
    for (const auto& [a, n] : count) total += n;
    std::string from;
    if (count[address] >= static_cast<std::size_t>(options.budgets.max_client_connections)) {
      from = address;
    } else if (total >= static_cast<std::size_t>(options.budgets.max_connections)) {
      std::size_t most = 0;
      for (const auto& [a, n] : count)
        if (n > most) most = n, from = a;
    } else {
      return true;
    }
    std::shared_ptr<SessionBase> victim;
    for (int pass = 0; pass < 2 && !victim; ++pass)  // the address first, then anyone
      for (const auto& s : all)
        if (s->waiting() && (pass == 1 || s->address == from) &&
            (!victim || s->last_activity < victim->last_activity))
          victim = s;
    if (!victim) return false;
    victim->evict();
    ++evicted;
    return true;
  }

  /// Reserves `bytes` of the body budget for `self`; bodies stalled for a second or more give
  /// way (least recently active first) when it does not fit. False: no room.
  bool reserve(std::size_t bytes, SessionBase* self) {
    if (body_in_use + bytes > options.budgets.body_budget_bytes()) {
      auto all = live();
      std::sort(all.begin(), all.end(),
                [](const auto& a, const auto& b) { return a->last_activity < b->last_activity; });
      const auto stalled = Clock::now() - std::chrono::seconds(1);
      for (const auto& s : all) {
        if (body_in_use + bytes <= options.budgets.body_budget_bytes()) break;
        if (s.get() == self || s->phase != Phase::Body || s->reserved == 0 ||
            s->last_activity > stalled)
          continue;
        s->evict();
        ++evicted;
      }
      if (body_in_use + bytes > options.budgets.body_budget_bytes()) return false;
    }
    body_in_use += bytes;
    self->reserved += bytes;
    return true;
  }

  void release(SessionBase* self) {
    body_in_use -= std::min(body_in_use, self->reserved);
    self->reserved = 0;
  }
};

/// One connection. Requests are read one at a time; an API call answers with "Connection: close"
/// (the connection ends with its result), health checks and static files keep the connection.
/// While a job runs the socket is watched, so a client that goes away cancels its job.
template <class Stream>
class HttpGateway::Impl::Session final : public SessionBase,
                                         public std::enable_shared_from_this<Session<Stream>> {
  static constexpr bool kTls = !std::is_same_v<Stream, beast::tcp_stream>;

 public:
  template <class... Args>
  explicit Session(Impl& gateway, Args&&... args)
      : gateway_(gateway), stream_(std::forward<Args>(args)...) {
    beast::error_code ec;
    const auto endpoint = beast::get_lowest_layer(stream_).socket().remote_endpoint(ec);
    if (!ec) address = endpoint.address().to_string();
    // Every close but the graceful one (close()) resets the connection: a timed-out or evicted
    // client's unsent bytes are dropped at once instead of staying in the kernel's buffers.
    beast::get_lowest_layer(stream_).socket().set_option(net::socket_base::linger(true, 0), ec);
    if (!ec)
      peer_ = std::string(endpoint.address().is_v6() ? "ipv6:[" : "ipv4:") +
              endpoint.address().to_string() + (endpoint.address().is_v6() ? "]:" : ":") +
              std::to_string(endpoint.port());
  }

  void run() {
    if constexpr (kTls) {
      beast::get_lowest_layer(stream_).expires_after(gateway_.options.budgets.stall_timeout());
      stream_.async_handshake(ssl::stream_base::server,
                              [self = this->shared_from_this()](beast::error_code ec) {
                                if (ec) return;  // not TLS, or gave up: drop the connection
                                self->read_request();
                              });
    } else {
      read_request();
    }
  }

  ~Session() override { gateway_.release(this); }

  void evict() override {
    gateway_.release(this);
    phase = Phase::Closing;
    abort();
  }

  void stop() override {
    if (reading_ && !job_active_)
      abort();  // idle between requests
    else
      stopping_ = true;  // close after the current response
  }

  // From the job's sink, on the I/O thread.
  void on_progress(const v1::Progress& event) {
    if (!sse_ || finished_) return;
    if (!headers_sent_) {
      // Headers go out with the first kernel progress: errors found while checking the request
      // (before the kernel starts) still get their own HTTP status.
      if (event.stage() == "queued") return;
      send_sse_headers();
    }
    std::string chunk = chunked("event: progress\ndata: " + to_json(event, false) + "\n\n");
    if (writing_) {  // a client that reads slowly gets the latest progress, not a backlog
      pending_progress_ = std::move(chunk);
      return;
    }
    send(std::move(chunk), false);
  }

  void on_finish(const Status& status, const std::string& result_json) {
    finished_ = true;
    job_active_ = false;
    pending_progress_.reset();
    if (sse_ && (headers_sent_ || status.ok())) {
      if (!headers_sent_) send_sse_headers();
      send_chunk(status.ok() ? "event: result\ndata: " + result_json + "\n\n"
                             : "event: error\ndata: " + error_json(status) + "\n\n");
      send("0\r\n\r\n", true);
      return;
    }
    if (status.ok())
      respond(http::status::ok, "application/json", result_json + "\n", false);
    else
      respond_error(status, false);
  }

 private:
  /// Holds the session until the job is finished (a job always finishes, within 200 ms of a
  /// cancellation), so the answer has somewhere to go; then lets go of it.
  class Sink final : public JobSink, public std::enable_shared_from_this<Sink> {
   public:
    Sink(std::shared_ptr<Session> session, net::any_io_executor executor)
        : session_(std::move(session)), executor_(std::move(executor)) {}

    void progress(const v1::Progress& event) override {
      {
        std::lock_guard lock(mutex_);
        if (!session_) return;
        pending_ = event;
        if (posted_) return;  // coalesce: the posted handler sends the latest
        posted_ = true;
      }
      net::post(executor_, [self = this->shared_from_this()] {
        v1::Progress event;
        std::shared_ptr<Session> session;
        {
          std::lock_guard lock(self->mutex_);
          event = std::move(self->pending_);
          self->posted_ = false;
          session = self->session_;
        }
        if (session) session->on_progress(event);
      });
    }

    void finish(const Status& status, std::unique_ptr<google::protobuf::Message> result) override {
      std::string json;
      Status final = status;
      if (result) {
        try {
          json = to_json(*result, false);  // on the worker, not the I/O thread
        } catch (const std::exception& e) {
          final = {StatusCode::Internal, e.what()};
        }
      }
      std::shared_ptr<Session> session;
      {
        std::lock_guard lock(mutex_);
        session = std::move(session_);
      }
      if (!session) return;
      net::post(executor_,
                [session, final, json = std::move(json)] { session->on_finish(final, json); });
    }

   private:
    std::mutex mutex_;
    std::shared_ptr<Session> session_;
    net::any_io_executor executor_;
    v1::Progress pending_;
    bool posted_ = false;
  };

  void read_request() {
    if (gateway_.stopping) return close();
    gateway_.release(this);  // the previous request's body is answered
    reading_ = true;
    phase = Phase::Idle;
    last_activity = Clock::now();
    parser_.emplace();
    parser_->header_limit(64 * 1024);
    parser_->body_limit(gateway_.options.body_limit);
    if (buffer_.size() > 0) return read_header();  // pipelined bytes are here already
    // Idle until the first byte; from then on the header has the stall timeout.
    beast::get_lowest_layer(stream_).expires_after(kIdleTimeout);
    stream_.async_read_some(buffer_.prepare(4096),
                            [self = this->shared_from_this()](beast::error_code ec, std::size_t n) {
                              if (ec) return self->fail_read(ec);
                              self->buffer_.commit(n);
                              self->read_header();
                            });
  }

  void read_header() {
    phase = Phase::Header;
    last_activity = Clock::now();
    beast::get_lowest_layer(stream_).expires_after(gateway_.options.budgets.stall_timeout());
    http::async_read_header(stream_, buffer_, *parser_,
                            [self = this->shared_from_this()](beast::error_code ec, std::size_t) {
                              self->on_header(ec);
                            });
  }

  void on_header(beast::error_code ec) {
    reading_ = false;
    if (ec) return fail_read(ec);
    if (closed_) return abort();
    auto& request = parser_->get();
    const std::string coding = lower(std::string(view(request[http::field::transfer_encoding])));
    if (!coding.empty() && coding != "chunked")
      return respond_error(
          {StatusCode::Unimplemented,
           "Transfer-Encoding: " + coding + " is not supported (send Content-Length or chunked)"},
          false, 501);
    const auto length = parser_->content_length();
    if (length && *length > gateway_.options.body_limit)
      return respond_error({StatusCode::ResourceExhausted, too_large_message()}, false, 413);
    const std::size_t need = length               ? *length
                             : parser_->chunked() ? gateway_.options.body_limit
                                                  : 0;
    if (need > 0 && !gateway_.reserve(need, this)) {
      retry_after_ = true;
      return respond_error({StatusCode::Unavailable,
                            "too many request bodies arriving at once (gridshelld "
                            "--http-body-budget-mib); retry in a second"},
                           false, 503);
    }
    if (lower(std::string(view(request[http::field::expect]))) == "100-continue")
      send("HTTP/1.1 100 Continue\r\n\r\n", false);
    reading_ = true;
    phase = Phase::Body;
    pace_start_ = last_activity = Clock::now();
    pace_bytes_ = 0;
    read_body();
  }

  /// The latest time the next bytes may come (or go): within the stall timeout, and never
  /// slower on average than the minimum rate once the stall timeout has passed.
  Clock::time_point pace_deadline() const {
    const HttpBudgets& b = gateway_.options.budgets;
    const auto by_rate = pace_start_ + b.stall_timeout() +
                         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                             static_cast<double>(pace_bytes_) / b.min_rate_bytes()));
    return std::min(Clock::now() + b.stall_timeout(), by_rate);
  }

  void read_body() {
    if (parser_->is_done()) return on_read({});
    beast::get_lowest_layer(stream_).expires_at(pace_deadline());
    http::async_read_some(stream_, buffer_, *parser_,
                          [self = this->shared_from_this()](beast::error_code ec, std::size_t n) {
                            if (ec) return self->fail_read(ec);
                            self->pace_bytes_ += n;
                            self->last_activity = Clock::now();
                            self->read_body();
                          });
  }

  void on_read(beast::error_code ec) {
    if (ec) return fail_read(ec);
    reading_ = false;
    phase = Phase::Busy;
    beast::get_lowest_layer(stream_).expires_never();
    handle(parser_->release());
  }

  void fail_read(beast::error_code ec) {
    reading_ = false;
    if (closed_) return abort();
    if (ec == http::error::body_limit)
      return respond_error({StatusCode::ResourceExhausted, too_large_message()}, false, 413);
    if (ec == beast::error::timeout && phase == Phase::Body)
      return respond_error({StatusCode::DeadlineExceeded,
                            "the request body stood still or arrived slower than " +
                                std::to_string(gateway_.options.budgets.min_rate_kib) +
                                " KiB/s (gridshelld --http-stall-timeout, --http-min-rate-kib)"},
                           false, 408);
    if (ec == http::error::end_of_stream || ec == net::error::eof || ec == beast::error::timeout ||
        ec == net::error::operation_aborted || ec == net::error::connection_reset ||
        ec.category() == net::error::get_ssl_category())
      return close();
    respond_error({StatusCode::InvalidArgument, "malformed HTTP request: " + ec.message()}, false,
                  400);
  }

  std::string too_large_message() const {
    const std::size_t limit = gateway_.options.body_limit;
    return "request body larger than the limit of " +
           (limit % (1u << 20) == 0 ? std::to_string(limit >> 20) + " MiB"
                                    : std::to_string(limit) + " bytes") +
           " (gridshelld --http-body-limit-mib)";
  }

  bool authorized(const http::request<http::string_body>& request) const {
    return bearer_token_matches(view(request[http::field::authorization]), gateway_.options.token);
  }

  void handle(http::request<http::string_body> request) {
    keep_alive_ = request.keep_alive() && !gateway_.stopping;
    cors_origin_.clear();
    allow_.clear();
    const std::string origin(view(request[http::field::origin]));
    if (!origin.empty())
      for (const std::string& allowed : gateway_.options.cors_origins)
        if (origin == allowed) cors_origin_ = origin;
    const std::string_view target(request.target().data(), request.target().size());
    const std::string path(target.substr(0, target.find('?')));
    const auto verb = request.method();

    if (path == "/healthz") {
      if (verb != http::verb::get && verb != http::verb::head) {
        allow_ = "GET, HEAD";
        return respond_error({StatusCode::Unimplemented, "use GET /healthz"}, keep_alive_, 405);
      }
      if (!authorized(request)) return unauthorized();
      const bool serving = gateway_.serving();
      return respond(serving ? http::status::ok : http::status::service_unavailable,
                     "application/json",
                     serving ? "{\"status\":\"SERVING\"}\n" : "{\"status\":\"NOT_SERVING\"}\n",
                     keep_alive_, verb == http::verb::head);
    }
    if (path.rfind("/v1/", 0) == 0) {
      const auto it = gateway_.routes.find(path);
      if (verb == http::verb::options && it != gateway_.routes.end()) return preflight();
      if (it == gateway_.routes.end())
        return respond_error(
            {StatusCode::NotFound,
             "no such method: " + path +
                 " (POST /v1/patch|design|simulate|run|geodesic|load|examples|fabricate|options)"},
            keep_alive_);
      if (verb != http::verb::post) {
        allow_ = "POST, OPTIONS";
        return respond_error({StatusCode::Unimplemented, "use POST " + path}, keep_alive_, 405);
      }
      if (!authorized(request)) return unauthorized();
      return start_job(std::move(request), it->second);
    }
    if (verb == http::verb::get || verb == http::verb::head)
      return serve_static(path, verb == http::verb::head);
    allow_ = "GET, HEAD";  // everything else is a static file
    respond_error({StatusCode::Unimplemented, "use GET " + path + " (static files)"}, keep_alive_,
                  405);
  }

  /// A CORS preflight: allowed for the configured origins only (the answer carries the
  /// Access-Control headers then; without them the browser refuses the call).
  void preflight() {
    if (cors_origin_.empty())
      return respond_error({StatusCode::PermissionDenied,
                            "cross-origin calls are not allowed "
                            "(gridshelld --cors-origin ORIGIN)"},
                           keep_alive_, 403);
    respond(http::status::no_content, "text/plain", "", keep_alive_);
  }

  void unauthorized() {
    respond_error({StatusCode::Unauthenticated,
                   "missing or wrong bearer token (header Authorization: Bearer TOKEN)"},
                  false);
  }

  void start_job(http::request<http::string_body> request, const Route& route) {
    keep_alive_ = false;  // an API call's connection ends with its result
    sse_ = view(request[http::field::accept]).find("text/event-stream") != std::string_view::npos;
    JobRequest job;
    job.id = gateway_.queue.next_id();
    request_id_ = std::to_string(job.id);
    job.method = route.name;
    job.transport = "http";
    job.light = route.light;
    job.peer = peer_;
    job.sink = std::make_shared<Sink>(this->shared_from_this(), stream_.get_executor());
    if (!route.implemented)
      return gateway_.queue.refuse(std::move(job),
                                   {StatusCode::Unimplemented, route.unimplemented});
    const std::string timeout(view(request["X-Timeout-Ms"]));
    if (!timeout.empty()) {
      char* end = nullptr;
      const double ms = std::strtod(timeout.c_str(), &end);
      if (end == timeout.c_str() || *end != '\0' || !(ms > 0) || ms > 1e9)
        return gateway_.queue.refuse(
            std::move(job),
            {StatusCode::InvalidArgument,
             "X-Timeout-Ms: expected a positive number of milliseconds, got '" + timeout + "'"});
      job.deadline = Clock::now() + std::chrono::microseconds(static_cast<long long>(ms * 1000));
    }
    job.run = route.job(std::make_shared<const std::string>(std::move(request.body())));
    job_active_ = true;
    watch_for_disconnect();
    job_ = gateway_.queue.submit(std::move(job));  // null if refused: the sink already has it
  }

  /// A read while the job runs: the client sends nothing more, so the read ends only when the
  /// connection does (or with stray bytes, which are ignored).
  void watch_for_disconnect() {
    watching_ = true;
    stream_.async_read_some(net::buffer(watch_buffer_), [self = this->shared_from_this()](
                                                            beast::error_code ec, std::size_t) {
      self->watching_ = false;
      if (self->closed_) return ec ? self->abort() : self->drain();
      if (!ec) {
        if (self->job_active_) self->watch_for_disconnect();
        return;
      }
      if (self->job_active_ && self->job_)
        self->gateway_.queue.cancel(self->job_, StatusCode::Cancelled, "the HTTP client went away");
    });
  }

  void serve_static(const std::string& target, bool head) {
    const Status not_found{StatusCode::NotFound, "not found: " + target};
    if (gateway_.static_root.empty()) return respond_error(not_found, keep_alive_);
    std::string path;
    if (!percent_decode(target, path) || path.empty() || path[0] != '/' ||
        path.find('\\') != std::string::npos)
      return respond_error(not_found, keep_alive_);
    if (path.back() == '/') path += "index.html";
    // No "..", no "." and no hidden files: a request never leaves the static folder.
    std::stringstream segments(path.substr(1));
    std::string segment;
    while (std::getline(segments, segment, '/'))
      if (segment.empty() || segment[0] == '.') return respond_error(not_found, keep_alive_);
    std::error_code ec;
    const fs::path file = fs::canonical(gateway_.static_root / path.substr(1), ec);
    const std::string root = gateway_.static_root.string() + "/";
    if (ec || file.string().rfind(root, 0) != 0 || !fs::is_regular_file(file, ec) ||
        fs::file_size(file, ec) > kMaxStaticFile)
      return respond_error(not_found, keep_alive_);
    // Streamed in chunks as the client reads them: a client that does not read holds one
    // chunk, not the file.
    const std::uint64_t size = fs::file_size(file, ec);
    auto in = std::make_unique<std::ifstream>(file, std::ios::binary);
    if (ec || !*in) return respond_error(not_found, keep_alive_);
    if (!head && size > 0) {
      file_ = std::move(in);
      file_left_ = size;
    }
    respond(http::status::ok, content_type(file), "", keep_alive_, head, size);
  }

  /// `streamed`: the length of a body that follows from file_ (the body argument is empty).
  void respond(http::status status, const char* type, std::string body, bool keep_alive,
               bool head = false, std::optional<std::uint64_t> streamed = std::nullopt) {
    http::response<http::string_body> response{status, 11};
    response.set(http::field::server, "gridshelld");
    response.set(http::field::content_type, type);
    response.set(http::field::cache_control, "no-store");
    if (!request_id_.empty()) response.set("X-Request-Id", request_id_);
    add_cors(response);
    if (status == http::status::unauthorized)
      response.set(http::field::www_authenticate, "Bearer realm=\"gridshelld\"");
    if (!allow_.empty()) response.set(http::field::allow, allow_);
    if (retry_after_) response.set(http::field::retry_after, "1");
    const std::uint64_t length = streamed ? *streamed : body.size();
    if (!head) response.body() = std::move(body);
    response.keep_alive(keep_alive);
    response.content_length(length);
    std::ostringstream text;
    text << response;
    std::string bytes = text.str();
    bytes.insert(bytes.find("\r\n") + 2, kSecurityHeaders);
    send(std::move(bytes), !keep_alive);
  }

  template <class Response>
  void add_cors(Response& response) const {
    if (cors_origin_.empty()) return;
    response.set(http::field::access_control_allow_origin, cors_origin_);
    response.set(http::field::vary, "Origin");
    response.set(http::field::access_control_allow_methods, "POST, OPTIONS");
    response.set(http::field::access_control_allow_headers,
                 "Content-Type, Authorization, Accept, X-Timeout-Ms");
    response.set(http::field::access_control_expose_headers, "X-Request-Id");
    response.set(http::field::access_control_max_age, "600");
  }

  void respond_error(const Status& status, bool keep_alive, int http_code = 0) {
    respond(static_cast<http::status>(http_code ? http_code : http_status(status.code)),
            "application/json", error_json(status) + "\n", keep_alive);
  }

  void send_sse_headers() {
    headers_sent_ = true;
    std::string header =
        "HTTP/1.1 200 OK\r\nServer: gridshelld\r\nContent-Type: text/event-stream\r\n"
        "Cache-Control: no-store\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n";
    header += kSecurityHeaders;
    if (!request_id_.empty()) header += "X-Request-Id: " + request_id_ + "\r\n";
    if (!cors_origin_.empty())
      header += "Access-Control-Allow-Origin: " + cors_origin_ +
                "\r\nVary: Origin\r\nAccess-Control-Expose-Headers: X-Request-Id\r\n";
    send(header + "\r\n", false);
  }

  static std::string chunked(const std::string& data) {
    std::ostringstream size;
    size << std::hex << data.size();
    return size.str() + "\r\n" + data + "\r\n";
  }
  void send_chunk(const std::string& data) { send(chunked(data), false); }

  /// Queues bytes; `last`: close the connection once they are written (otherwise, when nothing
  /// is left to write and no job is running, read the next request).
  void send(std::string bytes, bool last) {
    out_.push_back(std::move(bytes));
    if (last) close_after_write_ = true;
    if (!writing_) write_next();
  }

  void write_next() {
    if (out_.empty() && pending_progress_) {
      out_.push_back(std::move(*pending_progress_));
      pending_progress_.reset();
    }
    if (out_.empty() && file_) {
      std::string chunk(std::min<std::uint64_t>(file_left_, kWriteChunk), '\0');
      file_->read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
      if (file_->gcount() != static_cast<std::streamsize>(chunk.size())) {
        file_.reset();  // the file shrank: the length sent cannot be kept, end the connection
        out_.clear();
        return abort();
      }
      file_left_ -= chunk.size();
      if (file_left_ == 0) file_.reset();
      out_.push_back(std::move(chunk));
    }
    if (out_.empty()) {
      pacing_ = false;
      if (close_after_write_ || (stopping_ && !job_active_)) return close();
      if (!job_active_ && !reading_ && keep_alive_) read_request();
      return;
    }
    if (!pacing_) {  // an answer starts: it must move like a body does (pace_deadline)
      pacing_ = true;
      pace_start_ = Clock::now();
      pace_bytes_ = 0;
    }
    writing_ = true;
    // Sets the write timer (and the read timer unless a read is pending: the watch for a
    // disconnect, or a request being read, keeps its own).
    beast::get_lowest_layer(stream_).expires_at(pace_deadline());
    const std::string& front = out_.front();
    const std::size_t size = std::min(front.size() - written_, kWriteChunk);
    stream_.async_write_some(
        net::buffer(front.data() + written_, size),
        [self = this->shared_from_this()](beast::error_code ec, std::size_t n) {
          self->writing_ = false;
          if (ec) {
            if (self->job_active_ && self->job_)
              self->gateway_.queue.cancel(self->job_, StatusCode::Cancelled,
                                          "the HTTP client went away");
            self->out_.clear();
            self->written_ = 0;
            self->file_.reset();
            self->pending_progress_.reset();
            return ec == beast::error::timeout ? self->abort() : self->close();
          }
          self->pace_bytes_ += n;
          self->written_ += n;
          if (self->written_ == self->out_.front().size()) {
            self->out_.pop_front();
            self->written_ = 0;
          }
          self->write_next();
        });
  }

  /// Ends the connection gracefully: no more sending, then read (and drop) until the client
  /// closes too, so a close never resets the connection before the client has read everything.
  void close() {
    if (closed_) return;
    closed_ = true;
    phase = Phase::Closing;
    beast::error_code ec;
    beast::get_lowest_layer(stream_).socket().set_option(net::socket_base::linger(false, 0), ec);
    beast::get_lowest_layer(stream_).socket().shutdown(tcp::socket::shutdown_send, ec);
    beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(5));
    if (!watching_ && !reading_) return drain();
    // A pending read (the watch for a disconnect has no time limit) ends with the connection
    // and drains; a client that keeps the connection open anyway is cut after 5 s.
    drain_timer_.expires_after(std::chrono::seconds(5));
    drain_timer_.async_wait([self = this->shared_from_this()](beast::error_code ec) {
      if (!ec) self->abort();
    });
  }

  void drain() {
    beast::get_lowest_layer(stream_).async_read_some(
        net::buffer(watch_buffer_),
        [self = this->shared_from_this()](beast::error_code ec, std::size_t) {
          if (ec) return self->abort();
          self->drain();
        });
  }

  void abort() {
    closed_ = true;
    phase = Phase::Closing;
    beast::error_code ignored;
    beast::get_lowest_layer(stream_).socket().close(ignored);
  }

  Impl& gateway_;
  Stream stream_;
  net::steady_timer drain_timer_{stream_.get_executor()};
  std::string peer_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::deque<std::string> out_;
  std::size_t written_ = 0;                      ///< bytes of out_.front() already sent
  std::optional<std::string> pending_progress_;  ///< the latest progress while a write is out
  std::unique_ptr<std::ifstream> file_;          ///< a static file being sent, chunk by chunk
  std::uint64_t file_left_ = 0;
  Clock::time_point pace_start_;  ///< the body or answer in transfer began
  std::uint64_t pace_bytes_ = 0;  ///< bytes of it transferred
  bool pacing_ = false;           ///< an answer is being written (pace_start_ is its start)
  std::string allow_;             ///< the Allow header of a 405
  bool retry_after_ = false;      ///< a 503 with Retry-After
  std::array<char, 512> watch_buffer_{};
  std::shared_ptr<Job> job_;
  std::string request_id_;
  std::string cors_origin_;  ///< the request's Origin when it is allowed (CORS), else empty
  bool reading_ = false, writing_ = false, watching_ = false, closed_ = false, keep_alive_ = false;
  bool close_after_write_ = false, stopping_ = false;
  bool job_active_ = false, finished_ = false, sse_ = false, headers_sent_ = false;
};

void HttpGateway::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (!acceptor.is_open() || stopping) return;
      // Out of file descriptors (or another transient failure): try again shortly instead of
      // spinning on the error.
      accept_backoff.expires_after(std::chrono::milliseconds(50));
      accept_backoff.async_wait([this](beast::error_code) {
        if (acceptor.is_open() && !stopping) accept();
      });
      return;
    }
    beast::error_code ignored;
    const auto endpoint = socket.remote_endpoint(ignored);
    if (!admit(ignored ? std::string() : endpoint.address().to_string())) {
      // Every connection is busy with an answer: refuse this one, politely if it is plain HTTP.
      if (!tls) {
        static const std::string kBusy =
            "HTTP/1.1 503 Service Unavailable\r\nServer: gridshelld\r\nRetry-After: 1\r\n"
            "Content-Length: 0\r\nConnection: close\r\n\r\n";
        socket.non_blocking(true, ignored);
        socket.write_some(net::buffer(kBusy), ignored);
      }
      socket.close(ignored);
    } else if (tls) {
      auto session = std::make_shared<Session<beast::ssl_stream<beast::tcp_stream>>>(
          *this, std::move(socket), *tls);
      sessions.push_back(session);
      session->run();
    } else {
      auto session = std::make_shared<Session<beast::tcp_stream>>(*this, std::move(socket));
      sessions.push_back(session);
      session->run();
    }
    accept();
  });
}

HttpGateway::HttpGateway(HttpOptions options, JobQueue& queue, const Methods& methods,
                         std::function<bool()> serving)
    : impl_(std::make_unique<Impl>(std::move(options), queue, methods, std::move(serving))) {}

HttpGateway::~HttpGateway() { stop(); }

void HttpGateway::start() {
  Impl& g = *impl_;
  if (!g.options.static_dir.empty()) {
    std::error_code ec;
    g.static_root = fs::canonical(g.options.static_dir, ec);
    if (ec || !fs::is_directory(g.static_root))
      throw InvalidInput("--static", "" + g.options.static_dir + " is not a folder");
  }
  if (!g.options.tls_cert_pem.empty()) {
    g.tls.emplace(ssl::context::tls_server);
    g.tls->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 |
                       ssl::context::no_sslv3 | ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
    beast::error_code ec;
    g.tls->use_certificate_chain(net::buffer(g.options.tls_cert_pem), ec);
    if (ec) throw InvalidInput("--tls-cert", "not a PEM certificate chain: " + ec.message());
    g.tls->use_private_key(net::buffer(g.options.tls_key_pem), ssl::context::pem, ec);
    if (ec)
      throw InvalidInput("--tls-key", "not a PEM private key for the certificate: " + ec.message());
  }
  const auto [host, port] = split_host_port(g.options.address);
  beast::error_code ec;
  tcp::resolver resolver(g.io);
  const auto endpoints = resolver.resolve(host, port, tcp::resolver::passive, ec);
  if (ec || endpoints.empty())
    throw InvalidInput("--http", "cannot resolve " + g.options.address + ": " + ec.message());
  const tcp::endpoint endpoint = *endpoints.begin();
  g.acceptor.open(endpoint.protocol(), ec);
  if (!ec) g.acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) g.acceptor.bind(endpoint, ec);
  if (!ec) g.acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    throw InvalidInput("--http", "cannot listen on " + g.options.address + ": " + ec.message());
  g.port = g.acceptor.local_endpoint().port();
  g.accept();
  g.thread = std::thread([&g] {
    g.io.run();
    std::lock_guard lock(g.exit_mutex);
    g.exited = true;
    g.exited_cv.notify_all();
  });
}

int HttpGateway::port() const { return impl_->port; }

void HttpGateway::stop() {
  Impl& g = *impl_;
  {
    std::lock_guard lock(g.exit_mutex);
    if (g.stopped) return;
    g.stopped = true;
  }
  if (!g.thread.joinable()) return;
  net::post(g.io, [&g] {
    g.stopping = true;
    beast::error_code ignored;
    g.acceptor.close(ignored);
    g.accept_backoff.cancel();
    for (const auto& weak : g.sessions)
      if (auto session = weak.lock()) session->stop();
  });
  std::unique_lock lock(g.exit_mutex);
  if (!g.exited_cv.wait_for(lock, std::chrono::seconds(3), [&] { return g.exited; })) g.io.stop();
  lock.unlock();
  g.thread.join();
}

}  // namespace gridshell::server
