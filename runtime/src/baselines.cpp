#include <cstreams/runtime/baselines.hpp>
#include <cstreams/runtime/context.hpp>

#include <boost/compute/algorithm/copy_if.hpp>
#include <boost/compute/algorithm/exclusive_scan.hpp>
#include <boost/compute/command_queue.hpp>
#include <boost/compute/container/vector.hpp>
#include <boost/compute/context.hpp>
#include <boost/compute/function.hpp>

namespace cstreams::runtime {

namespace bc = boost::compute;

struct BoostComputeBaselines::Impl {
  bc::context context;
  bc::command_queue queue;
};

BoostComputeBaselines::BoostComputeBaselines(Context& context)
    : impl_(new Impl{bc::context(context.get(), true), bc::command_queue(context.queue(), true)})
{
}

BoostComputeBaselines::~BoostComputeBaselines() = default;

void BoostComputeBaselines::exclusive_scan(const Buffer& in, const Buffer& out, std::size_t n)
{
  bc::buffer src(in.get(), true), dst(out.get(), true);
  bc::exclusive_scan(bc::make_buffer_iterator<cl_uint>(src, 0), bc::make_buffer_iterator<cl_uint>(src, n),
                     bc::make_buffer_iterator<cl_uint>(dst, 0), impl_->queue);
}

std::size_t BoostComputeBaselines::copy_if_odd(const Buffer& in, const Buffer& out, std::size_t n)
{
  BOOST_COMPUTE_FUNCTION(bool, is_odd, (cl_uint x), { return (x & 1) != 0; });
  bc::buffer src(in.get(), true), dst(out.get(), true);
  auto end = bc::copy_if(bc::make_buffer_iterator<cl_uint>(src, 0), bc::make_buffer_iterator<cl_uint>(src, n),
                         bc::make_buffer_iterator<cl_uint>(dst, 0), is_odd, impl_->queue);
  return std::size_t(end.get_index());
}

}  // namespace cstreams::runtime
