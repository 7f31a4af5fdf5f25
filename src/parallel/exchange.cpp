#include "parallel/exchange.hpp"

#include <algorithm>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "paloverde/parallel/partition.hpp"
#include "parallel/mpi_support.hpp"

namespace paloverde {
namespace parallel {
namespace {

class MpiReducer final : public Reducer {
public:
    explicit MpiReducer(MPI_Comm comm) : comm_(comm) {}
    void sum(std::span<ExactSum> sums) const override {
        if (sums.empty()) return;
        std::vector<std::int64_t> digits(sums.size() * ExactSum::kDigits);
        std::vector<std::int64_t> special(sums.size());
        for (std::size_t i = 0; i < sums.size(); ++i) {
            sums[i].normalize();
            std::copy(sums[i].digits().begin(), sums[i].digits().end(), digits.begin() + i * ExactSum::kDigits);
            special[i] = sums[i].special();
        }
        MPI_Allreduce(MPI_IN_PLACE, digits.data(), static_cast<int>(digits.size()), MPI_INT64_T, MPI_SUM, comm_);
        MPI_Allreduce(MPI_IN_PLACE, special.data(), static_cast<int>(special.size()), MPI_INT64_T, MPI_BOR, comm_);
        for (std::size_t i = 0; i < sums.size(); ++i) {
            std::copy(digits.begin() + i * ExactSum::kDigits, digits.begin() + (i + 1) * ExactSum::kDigits,
                      sums[i].digits().begin());
            sums[i].special() = special[i];
        }
    }
    void sum_counts(std::span<std::int64_t> counts) const override {
        if (counts.empty()) return;
        MPI_Allreduce(MPI_IN_PLACE, counts.data(), static_cast<int>(counts.size()), MPI_INT64_T, MPI_SUM, comm_);
    }
    void sum_wrapping(std::span<std::uint64_t> values) const override {
        if (values.empty()) return;
        MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_UINT64_T, MPI_SUM, comm_);
    }
    double min(double value) const override {
        MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MIN, comm_);
        return value;
    }
    double max(double value) const override {
        MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MAX, comm_);
        return value;
    }

private:
    MPI_Comm comm_;
};

class MpiHalo final : public Halo {
public:
    MpiHalo(MPI_Comm comm, int rank, int ranks, const ExchangeSchedule& schedule)
        : comm_(comm), rank_(rank), ranks_(ranks), schedule_(schedule) {}

    void update(std::span<double> values, int width) const override {
        if (schedule_.mode == ExchangeMode::Colored) colored(values, width);
        else root_relayed(values, width);
    }

private:
    static std::vector<double> pack(std::span<const double> values, int width, const std::vector<VertexId>& list) {
        std::vector<double> out(list.size() * static_cast<std::size_t>(width));
        for (std::size_t i = 0; i < list.size(); ++i)
            for (int c = 0; c < width; ++c) out[i * width + c] = values[static_cast<std::size_t>(list[i]) * width + c];
        return out;
    }
    static void unpack(std::span<double> values, int width, const std::vector<VertexId>& list, const double* in) {
        for (std::size_t i = 0; i < list.size(); ++i)
            for (int c = 0; c < width; ++c) values[static_cast<std::size_t>(list[i]) * width + c] = in[i * width + c];
    }

    // Color by color, each rank trades with at most one partner per color.
    void colored(std::span<double> values, int width) const {
        std::vector<double> incoming;
        for (const ExchangePartner& p : schedule_.partners) {
            const auto outgoing = pack(values, width, p.send);
            incoming.resize(p.receive.size() * static_cast<std::size_t>(width));
            MPI_Sendrecv(outgoing.data(), static_cast<int>(outgoing.size()), MPI_DOUBLE, p.rank, p.color,
                         incoming.data(), static_cast<int>(incoming.size()), MPI_DOUBLE, p.rank, p.color, comm_,
                         MPI_STATUS_IGNORE);
            unpack(values, width, p.receive, incoming.data());
        }
    }

    // Every rank sends all its outgoing values to rank 0, which forwards each block to its
    // destination: the paper's baseline.
    void root_relayed(std::span<double> values, int width) const {
        std::vector<int> counts(static_cast<std::size_t>(ranks_), 0);  // doubles to each destination
        std::vector<double> outgoing;
        for (int to = 0; to < ranks_; ++to)
            for (const ExchangePartner& p : schedule_.partners)
                if (p.rank == to) {
                    const auto block = pack(values, width, p.send);
                    outgoing.insert(outgoing.end(), block.begin(), block.end());
                    counts[to] = static_cast<int>(block.size());
                }
        std::vector<int> all_counts(rank_ == 0 ? static_cast<std::size_t>(ranks_) * ranks_ : 0);
        MPI_Gather(counts.data(), ranks_, MPI_INT, all_counts.data(), ranks_, MPI_INT, 0, comm_);
        std::vector<int> gathered_sizes(rank_ == 0 ? ranks_ : 0), gathered_offsets(rank_ == 0 ? ranks_ : 0);
        std::vector<double> gathered;
        if (rank_ == 0) {
            int offset = 0;
            for (int from = 0; from < ranks_; ++from) {
                gathered_offsets[from] = offset;
                gathered_sizes[from] = std::accumulate(all_counts.begin() + from * ranks_, all_counts.begin() + (from + 1) * ranks_, 0);
                offset += gathered_sizes[from];
            }
            gathered.resize(static_cast<std::size_t>(offset));
        }
        MPI_Gatherv(outgoing.data(), static_cast<int>(outgoing.size()), MPI_DOUBLE, gathered.data(),
                    gathered_sizes.data(), gathered_offsets.data(), MPI_DOUBLE, 0, comm_);
        // Rank 0 regroups by destination, sources in rank order.
        std::vector<double> forward;
        std::vector<int> forward_sizes(rank_ == 0 ? ranks_ : 0), forward_offsets(rank_ == 0 ? ranks_ : 0);
        if (rank_ == 0) {
            for (int to = 0; to < ranks_; ++to) {
                forward_offsets[to] = static_cast<int>(forward.size());
                for (int from = 0; from < ranks_; ++from) {
                    int within = 0;
                    for (int d = 0; d < to; ++d) within += all_counts[from * ranks_ + d];
                    const double* block = gathered.data() + gathered_offsets[from] + within;
                    forward.insert(forward.end(), block, block + all_counts[from * ranks_ + to]);
                }
                forward_sizes[to] = static_cast<int>(forward.size()) - forward_offsets[to];
            }
        }
        std::size_t expected = 0;
        for (const ExchangePartner& p : schedule_.partners) expected += p.receive.size() * static_cast<std::size_t>(width);
        std::vector<double> incoming(expected);
        MPI_Scatterv(forward.data(), forward_sizes.data(), forward_offsets.data(), MPI_DOUBLE, incoming.data(),
                     static_cast<int>(incoming.size()), MPI_DOUBLE, 0, comm_);
        std::size_t offset = 0;
        for (int from = 0; from < ranks_; ++from)
            for (const ExchangePartner& p : schedule_.partners)
                if (p.rank == from) {
                    unpack(values, width, p.receive, incoming.data() + offset);
                    offset += p.receive.size() * static_cast<std::size_t>(width);
                }
    }

    MPI_Comm comm_;
    int rank_, ranks_;
    const ExchangeSchedule& schedule_;
};


}  // namespace

std::unique_ptr<Reducer> make_mpi_reducer(MPI_Comm comm) { return std::make_unique<MpiReducer>(comm); }
std::unique_ptr<Halo> make_mpi_halo(MPI_Comm comm, int rank, int ranks, const ExchangeSchedule& schedule) {
    return std::make_unique<MpiHalo>(comm, rank, ranks, schedule);
}

}  // namespace parallel

void DistributedMesh::build_schedule(ExchangeMode mode) {
    ExchangeSchedule& schedule = *schedule_;
    schedule = {};
    schedule.mode = mode;
    const auto ids = mesh_.global_ids();
    // Ghosts, grouped by owner (in canonical order within each group).
    std::vector<std::vector<VertexId>> receive(static_cast<std::size_t>(ranks_));
    for (VertexId v = 0; v < mesh_.num_vertices(); ++v)
        if (vertex_owner_[v] != rank_) receive[vertex_owner_[v]].push_back(v);
    // Tell each owner which of its vertices this rank holds.
    std::vector<int> request_counts(static_cast<std::size_t>(ranks_)), offer_counts(static_cast<std::size_t>(ranks_));
    for (int p = 0; p < ranks_; ++p) request_counts[p] = static_cast<int>(receive[p].size());
    MPI_Alltoall(request_counts.data(), 1, MPI_INT, offer_counts.data(), 1, MPI_INT, comm_);
    std::vector<int> request_offsets(static_cast<std::size_t>(ranks_), 0), offer_offsets(static_cast<std::size_t>(ranks_), 0);
    std::partial_sum(request_counts.begin(), request_counts.end() - 1, request_offsets.begin() + 1);
    std::partial_sum(offer_counts.begin(), offer_counts.end() - 1, offer_offsets.begin() + 1);
    std::vector<std::int64_t> requested;
    for (const auto& list : receive)
        for (VertexId v : list) requested.push_back(ids[v]);
    std::vector<std::int64_t> offered(static_cast<std::size_t>(offer_offsets.back() + offer_counts.back()));
    MPI_Alltoallv(requested.data(), request_counts.data(), request_offsets.data(), MPI_INT64_T, offered.data(),
                  offer_counts.data(), offer_offsets.data(), MPI_INT64_T, comm_);

    std::vector<std::pair<int, int>> my_edges;
    std::string failure;
    for (int p = 0; p < ranks_; ++p) {
        if (receive[p].empty() && offer_counts[p] == 0) continue;
        ExchangePartner partner;
        partner.rank = p;
        partner.receive = receive[p];
        for (int i = 0; i < offer_counts[p]; ++i) {
            const GlobalId id = offered[offer_offsets[p] + i];
            const auto it = std::lower_bound(ids.begin(), ids.end(), id);
            if (it == ids.end() || *it != id || vertex_owner_[it - ids.begin()] != rank_) {
                if (failure.empty())
                    failure = "rank " + std::to_string(p) + " holds vertex " + std::to_string(id) + " as owned by rank " +
                              std::to_string(rank_) + ", which does not own it";
                continue;
            }
            partner.send.push_back(static_cast<VertexId>(it - ids.begin()));
        }
        schedule.partners.push_back(std::move(partner));
        my_edges.push_back({std::min(rank_, p), std::max(rank_, p)});
    }
    parallel::agree(comm_, failure);
    // The whole process graph on every rank, colored the same way everywhere.
    int mine = static_cast<int>(my_edges.size());
    std::vector<int> edge_counts(static_cast<std::size_t>(ranks_));
    MPI_Allgather(&mine, 1, MPI_INT, edge_counts.data(), 1, MPI_INT, comm_);
    std::vector<int> edge_offsets(static_cast<std::size_t>(ranks_), 0);
    for (int p = 1; p < ranks_; ++p) edge_offsets[p] = edge_offsets[p - 1] + 2 * edge_counts[p - 1];
    std::vector<int> flat;
    for (const auto& [a, b] : my_edges) flat.push_back(a), flat.push_back(b);
    std::vector<int> flat_counts(static_cast<std::size_t>(ranks_));
    for (int p = 0; p < ranks_; ++p) flat_counts[p] = 2 * edge_counts[p];
    std::vector<int> all_flat(static_cast<std::size_t>(edge_offsets.back() + flat_counts.back()));
    MPI_Allgatherv(flat.data(), static_cast<int>(flat.size()), MPI_INT, all_flat.data(), flat_counts.data(),
                   edge_offsets.data(), MPI_INT, comm_);
    std::set<std::pair<int, int>> edge_set;
    for (std::size_t i = 0; i + 1 < all_flat.size(); i += 2) edge_set.insert({all_flat[i], all_flat[i + 1]});
    const std::vector<std::pair<int, int>> edges(edge_set.begin(), edge_set.end());
    const auto colors = color_process_graph(ranks_, edges);
    schedule.colors = colors.empty() ? 0 : *std::max_element(colors.begin(), colors.end()) + 1;
    for (ExchangePartner& p : schedule.partners) {
        const auto it = std::lower_bound(edges.begin(), edges.end(), std::pair{std::min(rank_, p.rank), std::max(rank_, p.rank)});
        p.color = colors[static_cast<std::size_t>(it - edges.begin())];
    }
    std::sort(schedule.partners.begin(), schedule.partners.end(),
              [](const ExchangePartner& a, const ExchangePartner& b) { return a.color < b.color; });
}

}  // namespace paloverde
