// SPDX-License-Identifier: GPL-3.0-or-later
#include "grpc_service.h"

#include <grpcpp/impl/codegen/proto_utils.h>

#include <mutex>
#include <optional>

#include "auth.h"

namespace gridshell::server {
namespace {

/// The status with the error as data in its details (v1::ErrorDetail), for clients that show
/// the field in their own terms; the message carries "field: message" for everyone else.
grpc::Status to_grpc(const Status& status) {
  if (status.ok()) return grpc::Status::OK;
  v1::ErrorDetail detail;
  detail.set_code(error_code_name(status.code));
  detail.set_field(status.field);
  detail.set_message(status.message);
  for (const v1::Suggestion& s : status.suggestions) *detail.add_suggestions() = s;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code), status.text(),
                      detail.SerializeAsString());
}

grpc::ByteBuffer to_bytes(const google::protobuf::Message& message) {
  grpc::ByteBuffer buffer;
  bool own = false;
  const grpc::Status status =
      grpc::SerializationTraits<google::protobuf::Message>::Serialize(message, &buffer, &own);
  if (!status.ok()) throw std::runtime_error("cannot serialize " + message.GetTypeName());
  return buffer;
}

/// One server-streaming call. The job (on a worker) reports through the Sink; the Sink turns
/// that into at most one outstanding write (progress events coalesce: only the latest waiting
/// one is sent), then the result and the status. gRPC operations are started outside the Sink's
/// lock, because their reactions may run on any thread. The reactor deletes itself in OnDone,
/// which gRPC calls only after Finish; the job finishes the Sink before that, and the Sink holds
/// everything the outstanding writes point to.
template <class Event, class Request>
class StreamReactor final : public grpc::ServerWriteReactor<grpc::ByteBuffer> {
  using Result = std::remove_pointer_t<decltype(std::declval<Event>().mutable_result())>;

 public:
  StreamReactor(JobQueue& queue, grpc::CallbackServerContext* context)
      : queue_(queue), context_(context), sink_(std::make_shared<Sink>(this)) {}

  /// The request, parsed from the call's bytes; lives until OnDone, after the job finished.
  Request request;

  std::shared_ptr<JobSink> sink() const { return sink_; }

  /// The job is queued (null if it was refused and is already finished).
  void attach(std::shared_ptr<Job> job) {
    bool cancel_now = false;
    {
      std::lock_guard lock(mutex_);
      job_ = job;
      cancel_now = cancelled_;
    }
    if (cancel_now) queue_.cancel(job, cancel_reason());
  }

  void OnCancel() override {
    std::shared_ptr<Job> job;
    {
      std::lock_guard lock(mutex_);
      cancelled_ = true;
      job = job_;
    }
    if (job) queue_.cancel(job, cancel_reason());
  }

  void OnWriteDone(bool ok) override { sink_->write_done(ok); }

  void OnDone() override { delete this; }

 private:
  /// Why gRPC cancelled the call. A client whose deadline passes cancels the stream itself,
  /// a little before the server's copy of the deadline (which started when the request arrived),
  /// so a cancellation just before the deadline counts as the deadline. Only the log and the
  /// statistics depend on it: the client already has its own status.
  StatusCode cancel_reason() const {
    const auto deadline = context_->deadline();
    return deadline != std::chrono::system_clock::time_point::max() &&
                   std::chrono::system_clock::now() + std::chrono::milliseconds(250) >= deadline
               ? StatusCode::DeadlineExceeded
               : StatusCode::Cancelled;
  }

  class Sink final : public JobSink {
   public:
    explicit Sink(StreamReactor* reactor) : reactor_(reactor) {}

    void progress(const v1::Progress& event) override {
      {
        std::lock_guard lock(mutex_);
        if (done_ || broken_) return;
        if (writing_) {
          pending_ = event;
          return;
        }
        writing_ = true;
        *current_.mutable_progress() = event;
        current_bytes_ = to_bytes(current_);
      }
      reactor_->StartWrite(&current_bytes_);
    }

    void finish(const Status& status, std::unique_ptr<google::protobuf::Message> result) override {
      {
        std::lock_guard lock(mutex_);
        if (done_) return;
        done_ = true;
        status_ = status;
        if (result && status.ok()) {
          final_.mutable_result()->Swap(static_cast<Result*>(result.get()));
          result.reset();
          final_bytes_ = to_bytes(final_);  // on the worker
          final_.Clear();
          has_result_ = true;
        }
        if (writing_) return;  // write_done finishes
      }
      send_final();
    }

    void write_done(bool ok) {
      bool final = false;
      {
        std::lock_guard lock(mutex_);
        writing_ = false;
        if (!ok) broken_ = true;  // the client is gone; OnCancel follows
        if (done_) {
          final = true;
        } else if (pending_ && !broken_) {
          *current_.mutable_progress() = std::move(*pending_);
          pending_.reset();
          current_bytes_ = to_bytes(current_);
          writing_ = true;
        } else {
          return;
        }
      }
      if (final)
        send_final();
      else
        reactor_->StartWrite(&current_bytes_);
    }

   private:
    void send_final() {
      if (!status_.ok())
        reactor_->Finish(to_grpc(status_));
      else if (has_result_ && !broken_)
        reactor_->StartWriteAndFinish(&final_bytes_, grpc::WriteOptions(), grpc::Status::OK);
      else  // a result nobody can receive any more
        reactor_->Finish(grpc::Status(grpc::StatusCode::CANCELLED, "the client went away"));
    }

    StreamReactor* reactor_;
    std::mutex mutex_;
    bool writing_ = false, done_ = false, broken_ = false, has_result_ = false;
    std::optional<v1::Progress> pending_;
    Event current_, final_;
    grpc::ByteBuffer current_bytes_;  // the write in flight
    grpc::ByteBuffer final_bytes_;    // the result, alive until OnDone
    Status status_;
  };

  JobQueue& queue_;
  grpc::CallbackServerContext* context_;
  std::shared_ptr<Sink> sink_;
  std::mutex mutex_;
  std::shared_ptr<Job> job_;
  bool cancelled_ = false;
};

std::string metadata(const grpc::CallbackServerContext* context, const char* key) {
  const auto& all = context->client_metadata();
  const auto it = all.find(key);
  return it == all.end() ? std::string() : std::string(it->second.data(), it->second.size());
}

class TokenProcessor final : public grpc::AuthMetadataProcessor {
 public:
  TokenProcessor(std::string token, std::function<void(const std::string&)> on_refused)
      : token_(std::move(token)), on_refused_(std::move(on_refused)) {}

  bool IsBlocking() const override { return false; }

  grpc::Status Process(const InputMetadata& metadata, grpc::AuthContext*, OutputMetadata*,
                       OutputMetadata*) override {
    const auto it = metadata.find("authorization");
    if (it != metadata.end() &&
        bearer_token_matches(std::string_view(it->second.data(), it->second.size()), token_))
      return grpc::Status::OK;
    const auto path = metadata.find(":path");
    if (on_refused_)
      on_refused_(path == metadata.end() ? std::string()
                                         : std::string(path->second.data(), path->second.size()));
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                        "missing or wrong bearer token (metadata authorization: Bearer TOKEN)");
  }

 private:
  std::string token_;
  std::function<void(const std::string&)> on_refused_;
};

}  // namespace

GridshellService::GridshellService(JobQueue& queue, const Methods& methods, std::string token)
    : queue_(queue), methods_(methods), token_(std::move(token)) {}

template <class Event, class M>
GridshellService::Reactor* GridshellService::serve(Context* context, const grpc::ByteBuffer* bytes,
                                                   const M& method) {
  auto* reactor = new StreamReactor<Event, typename M::Request>(queue_, context);
  JobRequest job;
  job.id = queue_.next_id();
  job.method = method.name;
  job.transport = "grpc";
  job.light = method.light;
  job.peer = context->peer();
  job.sink = reactor->sink();
  context->AddInitialMetadata("x-request-id", std::to_string(job.id));
  if (!bearer_token_matches(metadata(context, "authorization"), token_)) {
    queue_.refuse(std::move(job), {StatusCode::Unauthenticated,
                                   "missing or wrong bearer token (metadata authorization: "
                                   "Bearer TOKEN)"});
    return reactor;
  }
  grpc::ByteBuffer copy(*bytes);  // shares the slices; Deserialize consumes its argument
  if (!grpc::SerializationTraits<google::protobuf::Message>::Deserialize(&copy, &reactor->request)
           .ok()) {
    queue_.refuse(std::move(job),
                  {StatusCode::InvalidArgument, "request: not a " + reactor->request.GetTypeName() +
                                                    " (malformed protocol buffer bytes)"});
    return reactor;
  }
  if (!method.run) {
    queue_.refuse(std::move(job), {StatusCode::Unimplemented, method.unimplemented});
    return reactor;
  }
  const auto deadline = context->deadline();
  if (deadline != std::chrono::system_clock::time_point::max())
    job.deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      deadline - std::chrono::system_clock::now());
  job.run = job_function(method, &reactor->request);
  reactor->attach(queue_.submit(std::move(job)));
  return reactor;
}

#define GRIDSHELL_RPC(NAME, FIELD)                                                     \
  GridshellService::Reactor* GridshellService::NAME(Context* context,                  \
                                                    const grpc::ByteBuffer* request) { \
    return serve<v1::NAME##Event>(context, request, methods_.FIELD);                   \
  }
GRIDSHELL_RPC(Patch, patch)
GRIDSHELL_RPC(Design, design)
GRIDSHELL_RPC(Simulate, simulate)
GRIDSHELL_RPC(Run, run)
GRIDSHELL_RPC(Geodesic, geodesic)
GRIDSHELL_RPC(Load, load)
GRIDSHELL_RPC(Examples, examples)
GRIDSHELL_RPC(Fabricate, fabricate)
GRIDSHELL_RPC(Options, options)
GRIDSHELL_RPC(Layout, layout)
GRIDSHELL_RPC(RunLayout, run_layout)
#undef GRIDSHELL_RPC

std::shared_ptr<grpc::AuthMetadataProcessor> make_token_processor(
    std::string token, std::function<void(const std::string&)> on_refused) {
  return std::make_shared<TokenProcessor>(std::move(token), std::move(on_refused));
}

}  // namespace gridshell::server
